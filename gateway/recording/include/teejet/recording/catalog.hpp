#pragma once

// The teejet topics a recording holds, and how their samples travel between DDS and the bytes of
// an MCAP message without the caller knowing their types: the recorder takes samples as CDR (the
// serialized payload exactly as fastddsgen's type support writes it, encapsulation header
// included, which is what MCAP's "cdr" message encoding means), the replayer writes CDR back.
// docs/recording.md describes the file this makes.

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "teejet/core/result.hpp"
#include "teejet/dds/participant.hpp"

namespace teejet::recording {

inline constexpr const char* kSchemaEncoding = "omgidl";
inline constexpr const char* kMessageEncoding = "cdr";
// Disposals of a topic's instances go to a channel of their own, "<topic>/disposed", so that a
// plot of the topic never shows a disposal as a sample.
inline constexpr std::string_view kDisposedSuffix = "/disposed";
// Channel metadata keys: the DDS topic a channel replays to, and "disposed" on disposal channels.
inline constexpr const char* kDdsTopicKey = "dds_topic";
inline constexpr const char* kInstanceStateKey = "instance_state";
inline constexpr const char* kDisposed = "disposed";

// A recorded payload (CDR, encapsulation included) deserialized by `type` into `sample`, which
// must be of that type; an Error when the bytes are not one of its samples.
Status decode_payload(std::span<const std::uint8_t> bytes,
                      eprosima::fastdds::dds::TopicDataType& type, void* sample);

// The text of idl/teejet/valve.idl, built into the program: every schema's data.
std::string_view valve_idl();

using InstanceHandle = std::array<std::uint8_t, 16>;

struct TakenSample {
  std::uint64_t received_ns = 0;  // when this participant received it
  std::uint64_t source_ns = 0;    // the writer's source timestamp
  InstanceHandle instance{};      // zero for topics without a key
  InstanceHandle writer{};        // the writer's (its GUID): whose word it is
  // A disposal carries no data: `payload` is empty and the recorder names the instance from the
  // last sample it saw of it.
  bool disposed = false;
  // The instance has no writer left (its gateway stopped, or was lost): no data, nothing
  // happened to the valve, so nothing to record; a cache of the present forgets the instance.
  bool writers_gone = false;
  std::vector<std::uint8_t> payload;
};

class TopicReader {
 public:
  virtual ~TopicReader() = default;
  // Appends what is waiting, an instance whose writers all left as a sample with writers_gone.
  virtual void take(std::vector<TakenSample>& out) = 0;
  virtual eprosima::fastdds::dds::DataReader* reader() const = 0;
};

class TopicWriter {
 public:
  virtual ~TopicWriter() = default;
  // Publishes `payload` (as TakenSample::payload) with `source_ns` as its source timestamp.
  // A payload that does not deserialize into the topic's type is an Error, nothing is written.
  virtual Status write(std::span<const std::uint8_t> payload, std::uint64_t source_ns) = 0;
  // Disposes the instance whose key fields `payload` holds.
  virtual Status dispose(std::span<const std::uint8_t> payload, std::uint64_t source_ns) = 0;
  virtual int matched_readers() const = 0;
  // True once every matched reader acknowledged everything written, within `timeout`.
  virtual bool wait_for_acknowledgments(std::chrono::milliseconds timeout) = 0;
};

struct TopicType {
  std::string topic;      // "teejet/valve/position"
  std::string type_name;  // "teejet::ValvePosition": the schema name
  bool keyed = true;
  // TRANSIENT_LOCAL: its instances' last values are state (a split file starts with them);
  // commands and frames are events.
  bool durable = true;
  // With the QoS the topic's real readers and writers use (docs/topics.md), deeper where a
  // recorder must not lose what it is slow to take.
  Result<std::unique_ptr<TopicReader>> (*open_reader)(dds::Participant&) = nullptr;
  Result<std::unique_ptr<TopicWriter>> (*open_writer)(dds::Participant&) = nullptr;
};

// Every teejet topic, in the order of docs/topics.md.
const std::vector<TopicType>& topic_types();
const TopicType* find_topic(std::string_view topic);

// Shell-style glob ("teejet/valve/*", "*position"); '*' also matches '/'.
bool topic_matches(std::string_view glob, std::string_view topic);

}  // namespace teejet::recording
