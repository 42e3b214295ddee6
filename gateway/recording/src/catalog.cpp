#include "teejet/recording/catalog.hpp"

#include <fastdds/rtps/common/SerializedPayload.h>
#include <fnmatch.h>

#include <algorithm>
#include <cstring>
#include <exception>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>

#include "teejet/dds/participant.hpp"
#include "teejet/dds/source_stamps.hpp"
#include "teejet/dds/topics.hpp"

namespace teejet::recording {
namespace {

using namespace eprosima::fastdds::dds;
using eprosima::fastrtps::rtps::SerializedPayload_t;

// How the recorder's reader and the replayer's writer of a topic are set up.
enum class Kind {
  kState,          // RELIABLE, TRANSIENT_LOCAL: a late recorder gets every instance's value
  kCommandStatus,  // RELIABLE, TRANSIENT_LOCAL, 32 per valve
  kCommand,        // RELIABLE, VOLATILE: a command writer keeps nothing for late readers
  kFrame,          // BEST_EFFORT, VOLATILE
};

// The recorder's readers keep this many samples per instance that it has not taken yet: a
// state writer keeps only the last, but a recorder must not lose the one before it while it
// writes a chunk, nor while it waits for a CPU: 256 are 25 s of a valve's positions at the
// full poll rate (64 were 6.4 s). What reaches a starved recorder only after the writer has a
// newer sample of that instance is lost to it as to any reader (docs/performance.md, "Scale").
// Bounded, so that a stalled recorder cannot eat memory without limit: a backlog of every
// instance costs about 80 kB per instance and topic. Frames keep the frame reader's own QoS
// (best effort, 8192 held: about 3 s of a full bus).
constexpr std::int32_t kRecorderDepth = 256;

DataReaderQos recorder_qos(Kind kind) {
  DataReaderQos qos;
  switch (kind) {
    case Kind::kState:
      qos = dds::topics::state_reader_qos();
      break;
    case Kind::kCommandStatus:
      qos = dds::topics::status_reader_qos();
      break;
    case Kind::kCommand:
      // Not the gateway's KEEP_ALL command reader: a recorder that falls behind loses its own
      // oldest commands, never holds back a commander (a KEEP_LAST reader always accepts).
      qos = dds::topics::state_reader_qos();
      qos.durability().kind = VOLATILE_DURABILITY_QOS;
      break;
    case Kind::kFrame:
      return dds::topics::frame_reader_qos();
  }
  qos.history().kind = KEEP_LAST_HISTORY_QOS;
  qos.history().depth = std::max(qos.history().depth, kRecorderDepth);
  qos.resource_limits().max_samples_per_instance = qos.history().depth;
  qos.resource_limits().max_samples = qos.resource_limits().max_instances * qos.history().depth;
  return qos;
}

DataWriterQos replayer_qos(Kind kind) {
  switch (kind) {
    case Kind::kState:
      return dds::topics::state_writer_qos();
    case Kind::kCommandStatus:
      return dds::topics::status_writer_qos();
    case Kind::kCommand:
      return dds::topics::command_writer_qos();
    case Kind::kFrame:
      return dds::topics::frame_writer_qos();
  }
  return {};
}

std::uint64_t to_ns(const eprosima::fastrtps::rtps::Time_t& time) {
  const auto ns = time.to_ns();
  return ns > 0 ? static_cast<std::uint64_t>(ns) : 0;
}

Error dds_error(const std::string& what, const ReturnCode_t& code) {
  return Error{ErrorCode::kDds,
               what + " (Fast DDS return code " + std::to_string(static_cast<int>(code())) + ")"};
}

template <class Sample>
class TypedReader final : public TopicReader {
 public:
  explicit TypedReader(DataReader* reader) : reader_(reader) {}

  void take(std::vector<TakenSample>& out) override {
    Sample sample;
    SampleInfo info;
    while (reader_->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK) {
      TakenSample taken;
      taken.received_ns = to_ns(info.reception_timestamp);
      taken.source_ns = to_ns(info.source_timestamp);
      std::memcpy(taken.instance.data(), info.instance_handle.value, taken.instance.size());
      std::memcpy(taken.writer.data(), info.publication_handle.value, taken.writer.size());
      if (info.valid_data) {
        SerializedPayload_t payload(type_.getSerializedSizeProvider(&sample)());
        if (!type_.serialize(&sample, &payload)) continue;  // cannot happen for a taken sample
        taken.payload.assign(payload.data, payload.data + payload.length);
      } else if (info.instance_state == NOT_ALIVE_DISPOSED_INSTANCE_STATE) {
        taken.disposed = true;
      } else if (info.instance_state == NOT_ALIVE_NO_WRITERS_INSTANCE_STATE) {
        taken.writers_gone = true;
      } else {
        continue;  // one writer of several left: nothing happened to the valve
      }
      out.push_back(std::move(taken));
    }
  }

  DataReader* reader() const override { return reader_; }

 private:
  DataReader* reader_;
  typename PubSubTypeOf<Sample>::type type_;
};

template <class Sample>
class TypedWriter final : public TopicWriter {
 public:
  explicit TypedWriter(DataWriter* writer)
      : writer_(writer), held_(writer->get_qos().reliability().kind == RELIABLE_RELIABILITY_QOS) {}

  Status write(std::span<const std::uint8_t> payload, std::uint64_t source_ns) override {
    Sample sample;
    if (auto parsed = parse(payload, sample); !parsed) return parsed;
    // A replay of several gateways' samples goes back in time from one to the next; a reliable
    // writer holds such a stamp at the previous one (SourceStamps), a best-effort one need not.
    const auto code = stamped(source_ns, [&](const auto& stamp) {
      return writer_->write_w_timestamp(&sample, HANDLE_NIL, stamp);
    });
    if (code != ReturnCode_t::RETCODE_OK) return dds_error("write refused", code);
    return {};
  }

  Status dispose(std::span<const std::uint8_t> payload, std::uint64_t source_ns) override {
    Sample sample;
    if (auto parsed = parse(payload, sample); !parsed) return parsed;
    const auto code = stamped(source_ns, [&](const auto& stamp) {
      return writer_->dispose_w_timestamp(&sample, HANDLE_NIL, stamp);
    });
    if (code != ReturnCode_t::RETCODE_OK) return dds_error("dispose refused", code);
    return {};
  }

  int matched_readers() const override {
    PublicationMatchedStatus status;
    writer_->get_publication_matched_status(status);
    return status.current_count;
  }

  bool wait_for_acknowledgments(std::chrono::milliseconds timeout) override {
    return writer_->wait_for_acknowledgments(dds::to_dds_duration(timeout)) ==
           ReturnCode_t::RETCODE_OK;
  }

 private:
  Status parse(std::span<const std::uint8_t> bytes, Sample& sample) {
    return decode_payload(bytes, type_, &sample);
  }

  template <class Write>
  ReturnCode_t stamped(std::uint64_t source_ns, Write&& write) {
    if (!held_) return write(dds::to_dds_time(source_ns));
    return stamps_.write(source_ns, std::forward<Write>(write));
  }

  DataWriter* writer_;
  const bool held_;
  dds::SourceStamps stamps_;
  typename PubSubTypeOf<Sample>::type type_;
};

template <class Sample>
Result<std::unique_ptr<TopicReader>> open_reader(dds::Participant& participant, Kind kind) {
  auto topic = dds::topics::topic_of<Sample>(participant);
  if (!topic) return topic.error();
  // No listener: the recorder waits on the readers' status conditions.
  auto reader = participant.reader(*topic, recorder_qos(kind), nullptr, StatusMask::none());
  if (!reader) return reader.error();
  return std::unique_ptr<TopicReader>(std::make_unique<TypedReader<Sample>>(*reader));
}

template <class Sample>
Result<std::unique_ptr<TopicWriter>> open_writer(dds::Participant& participant, Kind kind) {
  auto topic = dds::topics::topic_of<Sample>(participant);
  if (!topic) return topic.error();
  auto writer = participant.writer(*topic, replayer_qos(kind));
  if (!writer) return writer.error();
  return std::unique_ptr<TopicWriter>(std::make_unique<TypedWriter<Sample>>(*writer));
}

// Commands and frames are events, statuses are kept 32 deep; everything else is state.
template <class Sample>
constexpr Kind kKindOf =
    std::is_same_v<Sample, ValveCommand> || std::is_same_v<Sample, LayoutChange> ? Kind::kCommand
    : std::is_same_v<Sample, CommandStatus> || std::is_same_v<Sample, LayoutChangeStatus>
        ? Kind::kCommandStatus
    : std::is_same_v<Sample, BusFrame> ? Kind::kFrame
                                       : Kind::kState;

template <class Sample>
TopicType entry() {
  constexpr Kind kKind = kKindOf<Sample>;
  const typename PubSubTypeOf<Sample>::type type;
  return TopicType{
      .topic = dds::topics::topic_name<Sample>(),
      .type_name = type.getName(),
      .keyed = type.m_isGetKeyDefined,
      .durable = kKind == Kind::kState || kKind == Kind::kCommandStatus,
      .open_reader =
          [](dds::Participant& participant) { return open_reader<Sample>(participant, kKind); },
      .open_writer =
          [](dds::Participant& participant) { return open_writer<Sample>(participant, kKind); }};
}

template <class... Samples>
std::vector<TopicType> entries(dds::topics::SampleTypes<Samples...>) {
  return {entry<Samples>()...};
}

}  // namespace

const std::vector<TopicType>& topic_types() {
  static const std::vector<TopicType> kTypes = entries(dds::topics::EverySampleType{});
  return kTypes;
}

const TopicType* find_topic(std::string_view topic) {
  const auto& types = topic_types();
  const auto found = std::find_if(types.begin(), types.end(),
                                  [&](const TopicType& type) { return type.topic == topic; });
  return found == types.end() ? nullptr : &*found;
}

bool topic_matches(std::string_view glob, std::string_view topic) {
  return ::fnmatch(std::string(glob).c_str(), std::string(topic).c_str(), 0) == 0;
}

Status decode_payload(std::span<const std::uint8_t> bytes,
                      eprosima::fastdds::dds::TopicDataType& type, void* sample) {
  SerializedPayload_t payload(static_cast<std::uint32_t>(bytes.size()));
  if (!bytes.empty()) std::memcpy(payload.data, bytes.data(), bytes.size());
  payload.length = static_cast<std::uint32_t>(bytes.size());
  const Error refused{ErrorCode::kInvalidValue, "a " + std::to_string(bytes.size()) +
                                                    "-byte payload is not a CDR " +
                                                    std::string(type.getName())};
  // fastcdr throws on a payload that ends early, which the type support turns into false, and
  // on an unknown encapsulation, a boolean that is not 0 or 1 or a string longer than its bound,
  // which it lets through.
  try {
    if (bytes.size() < 4 || !type.deserialize(&payload, sample)) return refused;
  } catch (const std::exception&) {
    return refused;
  }
  return {};
}

}  // namespace teejet::recording
