#pragma once

// The public DDS contract: topic names and the QoS each side uses. docs/topics.md says the same
// in words; tests/dds checks its topic table against this one.

#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <string>
#include <string_view>
#include <type_traits>

#include "teejet/codec/table.hpp"
#include "teejet/dds/conversions.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/valvePubSubTypes.h"

namespace teejet::dds::topics {

inline constexpr const char* kPresence = "teejet/valve/presence";
inline constexpr const char* kLocation = "teejet/valve/location";
inline constexpr const char* kError = "teejet/valve/error";
inline constexpr const char* kCommand = "teejet/valve/command";
inline constexpr const char* kCommandStatus = "teejet/valve/command_status";
inline constexpr const char* kLayoutChange = "teejet/layout/change";
inline constexpr const char* kLayoutChangeStatus = "teejet/layout/change_status";
inline constexpr const char* kGatewayStatus = "teejet/gateway/status";
inline constexpr const char* kBusFrame = "teejet/can/frame";
// Written once by each program that stays (gateway, teejet-web, teejet-record) and read by
// nobody: its offered deadline is the beat of the program's Fast DDS event thread
// (dds/event_watchdog.hpp). Not part of EverySampleType.
inline constexpr const char* kEventWatchdog = "teejet/event_watchdog";
// Telemetry: "teejet/valve/" and the subject of the message the sample carries (the codec's
// name of what its request asks for: position, current, cycle_counts, baud_rate, ...).
inline constexpr std::string_view kTelemetryPrefix = "teejet/valve/";
// A gateway's name is the key of its status (@key string<64>): a longer one would be cut when
// published, and two long names with a common start would become one gateway.
inline constexpr std::size_t kMaxGatewayNameLength = 64;

namespace detail {

inline std::string topic_of(std::type_identity<ValvePresence>) { return kPresence; }
inline std::string topic_of(std::type_identity<ValveLocation>) { return kLocation; }
inline std::string topic_of(std::type_identity<ValveError>) { return kError; }
inline std::string topic_of(std::type_identity<ValveCommand>) { return kCommand; }
inline std::string topic_of(std::type_identity<CommandStatus>) { return kCommandStatus; }
inline std::string topic_of(std::type_identity<LayoutChange>) { return kLayoutChange; }
inline std::string topic_of(std::type_identity<LayoutChangeStatus>) { return kLayoutChangeStatus; }
inline std::string topic_of(std::type_identity<GatewayStatus>) { return kGatewayStatus; }
inline std::string topic_of(std::type_identity<BusFrame>) { return kBusFrame; }

template <class Sample>
requires(kIsAlternative<Sample> && !std::is_same_v<Sample, ValveError>) std::string
    topic_of(std::type_identity<Sample>) {
  return std::string(kTelemetryPrefix) +
         std::string(codec::subject(from_sample(TelemetrySample{Sample{}})));
}

}  // namespace detail

// The topic each sample type is published on. A type without a topic does not compile.
template <class Sample>
const std::string& topic_name() {
  static const std::string name = detail::topic_of(std::type_identity<Sample>{});
  return name;
}

// A telemetry type's subject, its topic name without kTelemetryPrefix: the codec's name of the
// message it carries ("position", "cycle_counts").
template <class Sample>
requires(kIsAlternative<Sample> && !std::is_same_v<Sample, ValveError>) std::string
    telemetry_subject() {
  return topic_name<Sample>().substr(kTelemetryPrefix.size());
}

// The topic of `Sample` in `participant`, registering its type support on first use.
template <class Sample>
Result<eprosima::fastdds::dds::Topic*> topic_of(Participant& participant) {
  return participant.topic<typename PubSubTypeOf<Sample>::type>(topic_name<Sample>());
}

// Every sample type of the contract, in the order of docs/topics.md: presence, the locations,
// the telemetry (errors last), the commands and their statuses, the layout changes and theirs,
// the gateways' status and the raw frames.
template <class... Samples>
struct SampleTypes {};
template <class... Telemetry>
constexpr auto every_sample_type(std::type_identity<std::variant<Telemetry...>>) {
  return SampleTypes<ValvePresence, ValveLocation, Telemetry..., ValveCommand, CommandStatus,
                     LayoutChange, LayoutChangeStatus, GatewayStatus, BusFrame>{};
}
using EverySampleType = decltype(every_sample_type(std::type_identity<TelemetrySample>{}));

// Every profile allows 4096 instances (valves, or valve and error kind) per topic.

// State topics (presence, locations, telemetry, errors, gateway status): RELIABLE, TRANSIENT_LOCAL,
// KEEP_LAST 1 per instance. A late joiner gets the current value of every valve at once, and a
// BEST_EFFORT or VOLATILE reader still matches.
eprosima::fastdds::dds::DataWriterQos state_writer_qos();
eprosima::fastdds::dds::DataReaderQos state_reader_qos();
// state_reader_qos() that also follows its writers' liveliness (3 s, as the state writers offer):
// Fast DDS watches a writer's liveliness only for a reader that asks for a finite lease. A
// writer offering none (another vendor's, an older gateway) does not match it.
eprosima::fastdds::dds::DataReaderQos liveliness_reader_qos();
// state_reader_qos() BEST_EFFORT and VOLATILE: for state its writers resend every poll, where a
// lost sample is replaced by the next; no writer history reaches it (docs/topics.md, "A stream
// of state").
eprosima::fastdds::dds::DataReaderQos stream_reader_qos();

// Commands (and layout changes): RELIABLE, VOLATILE, KEEP_ALL (up to 256 queued per valve, writers
// heartbeat every 100 ms so acknowledgements free them promptly), so no command is lost; automatic
// liveliness with a 2 s lease lets the gateway notice a vanished commander.
eprosima::fastdds::dds::DataWriterQos command_writer_qos();
eprosima::fastdds::dds::DataReaderQos command_reader_qos();

// Command status (and layout change status): RELIABLE, TRANSIENT_LOCAL, KEEP_LAST 32 per valve: a
// reader that keeps up sees every transition; one that does not never stalls the gateway; and one
// that the gateway matched a moment before the reader matched the gateway still gets its ACCEPTED
// (the two sides of a match do not happen at once: a VOLATILE reader starts after the first
// heartbeat it hears and loses what that heartbeat already counted; measured with CycloneDDS 0.10,
// issue 8).
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
