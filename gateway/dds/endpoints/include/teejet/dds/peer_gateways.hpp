#pragma once

// The gateways this one hears on its domain, read from their GatewayStatus (TRANSIENT_LOCAL: a
// gateway that starts late hears the others at once). The count goes out in this gateway's own
// status as gateways_seen, so a client that has met one gateway knows how many to wait for. A
// second gateway publishing under this gateway's name is logged once per participant, and a
// serial that another gateway lists online while this one does too is logged when it starts and
// when it ends: both gateways see the other, so both say it.

#include <fastdds/rtps/common/Guid.h>
#include <fastdds/rtps/common/InstanceHandle.h>

#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "teejet/bridge/bridge.hpp"
#include "teejet/dds/participant.hpp"

namespace teejet::dds {

class PeerGateways final : public eprosima::fastdds::dds::DataReaderListener,
                           public bridge::OtherGateways {
 public:
  // `own_name` is this gateway's; `own_writer` its GatewayStatus writer, whose samples are not a
  // duplicate of the name.
  static Result<std::unique_ptr<PeerGateways>> create(
      Participant& participant, std::string own_name,
      const eprosima::fastrtps::rtps::GUID_t& own_writer);
  ~PeerGateways() override;
  PeerGateways(const PeerGateways&) = delete;
  PeerGateways& operator=(const PeerGateways&) = delete;

  // Gateways whose status writer is matched, this one included: at least 1. A writer that left,
  // or whose participant was dropped, is no longer counted.
  std::uint32_t count() const;

  std::vector<std::string> reporting_online(std::uint32_t serial) const override;

  void on_data_available(eprosima::fastdds::dds::DataReader* reader) override;
  void on_subscription_matched(
      eprosima::fastdds::dds::DataReader* reader,
      const eprosima::fastdds::dds::SubscriptionMatchedStatus& status) override;

 private:
  PeerGateways(Participant& participant, std::string own_name,
               const eprosima::fastrtps::rtps::GUID_t& own_writer);

  // A serial that this gateway and another both report online.
  struct Shared {
    std::uint32_t serial;
    std::string other;  // the other gateway's name
    eprosima::fastrtps::rtps::GuidPrefix_t participant;
    bool operator<(const Shared& other_one) const {
      return std::tie(serial, other, participant) <
             std::tie(other_one.serial, other_one.other, other_one.participant);
    }
  };
  std::set<Shared> shared_serials() const;  // mutex_ held
  // Logs the serials that began or ceased to be shared since the last call. mutex_ not held.
  void log_shared_serials();
  void forget_writer(const eprosima::fastrtps::rtps::InstanceHandle_t& writer);

  Participant& participant_;
  const std::string own_name_;
  const eprosima::fastrtps::rtps::GUID_t own_writer_;
  eprosima::fastdds::dds::DataReader* reader_ = nullptr;

  mutable std::mutex mutex_;
  std::set<eprosima::fastrtps::rtps::GuidPrefix_t> namesakes_;  // each logged once
  std::set<std::uint32_t> own_online_;                          // from this gateway's own status
  // The other gateways' writers of status, each with its name, instance and online serials.
  struct Other {
    std::string name;
    eprosima::fastrtps::rtps::InstanceHandle_t instance;
    std::set<std::uint32_t> online;
  };
  std::map<eprosima::fastrtps::rtps::GUID_t, Other> others_;
  std::set<Shared> logged_;  // the shared serials said so far
};

}  // namespace teejet::dds
