#include "teejet/dds/location_claims.hpp"

#include <spdlog/spdlog.h>

#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <vector>

#include "teejet/dds/topics.hpp"
#include "teejet/valvePubSubTypes.h"

namespace teejet::dds {

using namespace eprosima::fastdds::dds;

LocationClaims::LocationClaims(Participant& participant, std::string own_name,
                               std::set<std::string> own_locations)
    : participant_(participant),
      own_name_(std::move(own_name)),
      own_locations_(std::move(own_locations)) {}

Result<std::unique_ptr<LocationClaims>> LocationClaims::create(
    Participant& participant, std::string own_name, std::set<std::string> own_locations) {
  std::unique_ptr<LocationClaims> claims(
      new LocationClaims(participant, std::move(own_name), std::move(own_locations)));
  auto topic = topics::topic_of<ValveLocation>(participant);
  if (!topic) return topic.error();
  auto reader = participant.reader(*topic, topics::state_reader_qos(), claims.get(),
                                   StatusMask::data_available());
  if (!reader) return reader.error();
  claims->reader_ = *reader;
  return claims;
}

LocationClaims::~LocationClaims() { participant_.delete_reader(reader_); }

void LocationClaims::on_data_available(DataReader* reader) {
  // Taken before locking: Fast DDS holds the reader's lock while it calls the listener.
  std::vector<std::pair<std::string, std::string>> claimed;
  ValveLocation sample;
  SampleInfo info;
  while (reader->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK) {
    if (!info.valid_data) continue;
    std::string location = sample.location().to_string();
    std::string gateway = sample.gateway().to_string();
    if (gateway != own_name_ && own_locations_.contains(location)) {
      claimed.emplace_back(std::move(location), std::move(gateway));
    }
  }
  std::lock_guard lock(mutex_);
  for (auto& claim : claimed) {
    if (!contested_.insert(claim).second) continue;
    spdlog::error(
        "location {} of this gateway's layout is claimed by gateway {} too: an ECU that names it "
        "cannot tell which valve it means; rename it in one of the two layouts (docs/layout.md)",
        claim.first, claim.second);
  }
}

}  // namespace teejet::dds
