#pragma once

// The gateway's writers: the Sink the bridge publishes through. A telemetry sample carries the
// CAN receive time as its DDS source timestamp too, a presence its valve's last I'm Here, the
// others the time they were written; never earlier than the writer's previous sample
// (SourceStamps says why).

#include <fastdds/dds/publisher/DataWriter.hpp>
#include <memory>
#include <tuple>
#include <variant>

#include "teejet/bridge/bridge.hpp"
#include "teejet/dds/location_claims.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/dds/peer_gateways.hpp"
#include "teejet/dds/source_stamps.hpp"
#include "teejet/dds/topics.hpp"

namespace teejet::dds {

// One writer for each alternative of a sample variant, found by the sample's type. The topic
// comes from topics::topic_name<Sample>(): a sample type without a topic does not compile.
template <class Variant>
class SampleWriters;

template <class... Samples>
class SampleWriters<std::variant<Samples...>> {
 public:
  Status create(Participant& participant, const eprosima::fastdds::dds::DataWriterQos& qos) {
    Status created;
    (void)((created = create_one<Samples>(participant, qos), created.ok()) && ...);
    return created;
  }

  template <class Sample>
  eprosima::fastdds::dds::DataWriter* writer() const {
    return std::get<Slot<Sample>>(writers_).writer;
  }

  // Writes `sample` stamped `stamp_ns` (Unix nanoseconds; 0: now), or at the writer's previous
  // sample's stamp when that would go back.
  template <class Sample>
  eprosima::fastrtps::types::ReturnCode_t write(const Sample& sample, std::uint64_t stamp_ns) {
    auto& slot = std::get<Slot<Sample>>(writers_);
    const auto with = [&](const eprosima::fastrtps::Time_t& stamp) {
      return slot.writer->write_w_timestamp(const_cast<Sample*>(&sample),
                                            eprosima::fastdds::dds::HANDLE_NIL, stamp);
    };
    return stamp_ns == 0 ? slot.stamps->write_now(with) : slot.stamps->write(stamp_ns, with);
  }

  // Disposes the instance of `key`, stamped now on the same terms.
  template <class Sample>
  eprosima::fastrtps::types::ReturnCode_t dispose(const Sample& key) {
    auto& slot = std::get<Slot<Sample>>(writers_);
    return slot.stamps->write_now([&](const eprosima::fastrtps::Time_t& stamp) {
      return slot.writer->dispose_w_timestamp(const_cast<Sample*>(&key),
                                              eprosima::fastdds::dds::HANDLE_NIL, stamp);
    });
  }

 private:
  template <class Sample>
  struct Slot {
    eprosima::fastdds::dds::DataWriter* writer = nullptr;
    std::unique_ptr<SourceStamps> stamps = std::make_unique<SourceStamps>();
  };

  template <class Sample>
  Status create_one(Participant& participant, const eprosima::fastdds::dds::DataWriterQos& qos) {
    auto topic = topics::topic_of<Sample>(participant);
    if (!topic) return topic.error();
    auto writer = participant.writer(*topic, qos);
    if (!writer) return writer.error();
    std::get<Slot<Sample>>(writers_).writer = *writer;
    return {};
  }

  std::tuple<Slot<Samples>...> writers_;
};

class GatewayPublisher final : public bridge::Sink {
 public:
  // `gateway_name` is the one its statuses carry: the other gateways it hears are counted
  // against it (gateways_seen). `locations`: the names of its layout, which other gateways must
  // not claim too.
  static Result<std::unique_ptr<GatewayPublisher>> create(
      Participant& participant, const std::string& gateway_name,
      const std::set<std::string>& locations = {});

  void presence(const ValvePresence& sample) override;
  void location(const ValveLocation& sample) override;
  void telemetry(const TelemetrySample& sample) override;
  void error_cleared(std::uint32_t serial, ErrorKind kind) override;
  void command_status(const CommandStatus& status) override;
  void layout_change_status(const LayoutChangeStatus& status) override;
  void gateway_status(const GatewayStatus& status) override;

  // Waits until every matched reader acknowledged the statuses written so far, or `timeout`
  // passes: the last statuses of a shutdown must not go down with the writer. True when all
  // were acknowledged.
  bool wait_for_statuses(Duration timeout);

  // False when DDS-Security permissions made before layout changes existed do not let the
  // gateway answer them: it then neither takes them (a warning says what to grant).
  bool answers_layout_changes() const { return layout_status_ready_; }

  // The writer of Sample's topic: its matched readers are the clients that follow it.
  template <class Sample>
  eprosima::fastdds::dds::DataWriter* writer_of() const {
    if constexpr (kIsAlternative<Sample, TelemetrySample>) {
      return telemetry_.writer<Sample>();
    } else {
      return state_.writer<Sample>();
    }
  }

  // What the other gateways report (nullptr when their status cannot be read): for the bridge,
  // which refuses commands to a serial that another gateway reports online too.
  const bridge::OtherGateways* other_gateways() const { return peers_.get(); }

  // Deletes the reader of the other gateways' status. Call it before the participant goes,
  // which deletes the writers by itself but cannot be asked to delete a reader afterwards.
  void stop_hearing_peers() {
    peers_.reset();
    claims_.reset();
  }

 private:
  GatewayPublisher() = default;

  using StateSample = std::variant<ValvePresence, ValveLocation, GatewayStatus>;
  SampleWriters<TelemetrySample> telemetry_;
  SampleWriters<StateSample> state_;
  SampleWriters<std::variant<CommandStatus>> command_status_;
  SampleWriters<std::variant<LayoutChangeStatus>> layout_status_;
  bool layout_status_ready_ = false;
  std::unique_ptr<PeerGateways> peers_;
  std::unique_ptr<LocationClaims> claims_;  // only with a layout
};

}  // namespace teejet::dds
