#pragma once

// The places other gateways on the domain claim (teejet/valve/location), held against this
// gateway's own: a machine with several buses has one name space of locations, and an ECU that
// resolves a name two gateways claim cannot tell which valve it means. Each such name is logged
// once per other gateway, by both gateways, since each hears the other.

#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <utility>

#include "teejet/dds/participant.hpp"

namespace teejet::dds {

class LocationClaims final : public eprosima::fastdds::dds::DataReaderListener {
 public:
  // `own_locations`: the names in this gateway's layout, which no change alters.
  static Result<std::unique_ptr<LocationClaims>> create(Participant& participant,
                                                        std::string own_name,
                                                        std::set<std::string> own_locations);
  ~LocationClaims() override;
  LocationClaims(const LocationClaims&) = delete;
  LocationClaims& operator=(const LocationClaims&) = delete;

  void on_data_available(eprosima::fastdds::dds::DataReader* reader) override;

 private:
  LocationClaims(Participant& participant, std::string own_name,
                 std::set<std::string> own_locations);

  Participant& participant_;
  const std::string own_name_;
  const std::set<std::string> own_locations_;
  eprosima::fastdds::dds::DataReader* reader_ = nullptr;
  std::mutex mutex_;
  std::set<std::pair<std::string, std::string>> contested_;  // (location, other gateway) logged
};

}  // namespace teejet::dds
