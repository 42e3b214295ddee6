#pragma once

// The public DDS contract: topic names and the QoS each side uses. docs/topics.md says the same
// in words; change both together.

#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>

#include "teejet/valvePubSubTypes.h"

namespace teejet::dds::topics {

inline constexpr const char* kPresence = "teejet/valve/presence";
inline constexpr const char* kPosition = "teejet/valve/position";
inline constexpr const char* kVersion = "teejet/valve/version";
inline constexpr const char* kTemperature = "teejet/valve/temperature";
inline constexpr const char* kVoltage = "teejet/valve/voltage";
inline constexpr const char* kCurrent = "teejet/valve/current";
inline constexpr const char* kDegreesPerSecond = "teejet/valve/degrees_per_second";
inline constexpr const char* kSpeedDirection = "teejet/valve/speed_direction";
inline constexpr const char* kRunTime = "teejet/valve/run_time";
inline constexpr const char* kCycleCount = "teejet/valve/cycle_count";
inline constexpr const char* kBaudRate = "teejet/valve/baud_rate";
inline constexpr const char* kError = "teejet/valve/error";
inline constexpr const char* kCommand = "teejet/valve/command";
inline constexpr const char* kCommandStatus = "teejet/valve/command_status";
inline constexpr const char* kGatewayStatus = "teejet/gateway/status";
inline constexpr const char* kBusFrame = "teejet/can/frame";

// The topic each sample type is published on, and its fastddsgen type support. There is no
// entry for a type without a topic: using one is a compile error ("incomplete type").
template <class Sample>
struct TopicOf;

#define TEEJET_TOPIC_OF(Sample, topic_name)          \
  template <>                                        \
  struct TopicOf<Sample> {                           \
    static constexpr const char* kName = topic_name; \
    using PubSubType = Sample##PubSubType;           \
  }
TEEJET_TOPIC_OF(ValvePresence, kPresence);
TEEJET_TOPIC_OF(ValveVersion, kVersion);
TEEJET_TOPIC_OF(ValvePosition, kPosition);
TEEJET_TOPIC_OF(ValveTemperature, kTemperature);
TEEJET_TOPIC_OF(ValveVoltage, kVoltage);
TEEJET_TOPIC_OF(ValveCurrent, kCurrent);
TEEJET_TOPIC_OF(ValveDegreesPerSecond, kDegreesPerSecond);
TEEJET_TOPIC_OF(ValveSpeedDirection, kSpeedDirection);
TEEJET_TOPIC_OF(ValveRunTime, kRunTime);
TEEJET_TOPIC_OF(ValveCycleCount, kCycleCount);
TEEJET_TOPIC_OF(ValveBaudRate, kBaudRate);
TEEJET_TOPIC_OF(ValveError, kError);
TEEJET_TOPIC_OF(ValveCommand, kCommand);
TEEJET_TOPIC_OF(CommandStatus, kCommandStatus);
TEEJET_TOPIC_OF(GatewayStatus, kGatewayStatus);
TEEJET_TOPIC_OF(BusFrame, kBusFrame);
#undef TEEJET_TOPIC_OF

// Every profile allows 4096 instances (valves, or valve and error kind) per topic.

// State topics (presence, telemetry, errors, gateway status): RELIABLE, TRANSIENT_LOCAL,
// KEEP_LAST 1 per instance. A late joiner gets the current value of every valve at once, and a
// BEST_EFFORT or VOLATILE reader still matches.
eprosima::fastdds::dds::DataWriterQos state_writer_qos();
eprosima::fastdds::dds::DataReaderQos state_reader_qos();

// Commands: RELIABLE, VOLATILE, KEEP_ALL (up to 256 queued per valve, writers heartbeat every
// 100 ms so acknowledgements free them promptly), so no command is lost;
// automatic liveliness with a 2 s lease lets the gateway notice a vanished commander.
eprosima::fastdds::dds::DataWriterQos command_writer_qos();
eprosima::fastdds::dds::DataReaderQos command_reader_qos();

// Command status: RELIABLE, TRANSIENT_LOCAL, KEEP_LAST 32 per valve: a reader that keeps up sees
// every transition; one that does not never stalls the gateway; and one that the gateway matched
// a moment before the reader matched the gateway still gets its ACCEPTED (the two sides of a
// match do not happen at once: a VOLATILE reader starts after the first heartbeat it hears and
// loses what that heartbeat already counted; measured with CycloneDDS 0.10, issue 8).
eprosima::fastdds::dds::DataWriterQos status_writer_qos();
eprosima::fastdds::dds::DataReaderQos status_reader_qos();

// Raw bus frames (only from a gateway started with --record-frames): BEST_EFFORT, VOLATILE,
// KEEP_LAST, one keyless instance. A reader that is slow or gone never slows the gateway, which
// publishes on the thread that read or sent the frame; it loses the oldest frames instead.
// Writer depth 256: a best-effort writer sends inside write() and never resends, so its history
// only has to cover the bursts of a receive batch (64) while a local reader copies them. Reader
// depth 8192: three seconds of a full 32-valve bus polled every 0.1 s (2,600 frames/s measured,
// docs/performance.md), so a recorder that takes its samples a few times a second loses none.
eprosima::fastdds::dds::DataWriterQos frame_writer_qos();
eprosima::fastdds::dds::DataReaderQos frame_reader_qos();

}  // namespace teejet::dds::topics
