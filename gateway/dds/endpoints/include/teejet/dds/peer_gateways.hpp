#pragma once

// The gateways this one hears on its domain, read from their GatewayStatus (TRANSIENT_LOCAL: a
// gateway that starts late hears the others at once). The count goes out in this gateway's own
// status as gateways_seen, so a client that has met one gateway knows how many to wait for. A
// second gateway publishing under this gateway's name is logged once per participant: both
// gateways see the other, so both say it.

#include <fastdds/rtps/common/Guid.h>
#include <fastdds/rtps/common/InstanceHandle.h>

#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>

#include "teejet/dds/participant.hpp"

namespace teejet::dds {

class PeerGateways final : public eprosima::fastdds::dds::DataReaderListener {
 public:
  // `own_name` is this gateway's; `own_writer` its GatewayStatus writer, whose samples are not a
  // duplicate of the name.
  static Result<std::unique_ptr<PeerGateways>> create(
      Participant& participant, std::string own_name,
      const eprosima::fastrtps::rtps::GUID_t& own_writer);
  ~PeerGateways() override;
  PeerGateways(const PeerGateways&) = delete;
  PeerGateways& operator=(const PeerGateways&) = delete;

  // Gateways whose status instance is alive, this one included: at least 1.
  std::uint32_t count() const;

  void on_data_available(eprosima::fastdds::dds::DataReader* reader) override;

 private:
  PeerGateways(Participant& participant, std::string own_name,
               const eprosima::fastrtps::rtps::GUID_t& own_writer);

  Participant& participant_;
  const std::string own_name_;
  const eprosima::fastrtps::rtps::GUID_t own_writer_;
  eprosima::fastdds::dds::DataReader* reader_ = nullptr;

  mutable std::mutex mutex_;
  std::map<eprosima::fastrtps::rtps::InstanceHandle_t, std::string> alive_;  // by instance
  std::set<eprosima::fastrtps::rtps::GuidPrefix_t> namesakes_;               // each logged once
};

}  // namespace teejet::dds
