#include "teejet/dds/peer_gateways.hpp"

#include <spdlog/spdlog.h>

#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <vector>

#include "teejet/dds/topics.hpp"
#include "teejet/valvePubSubTypes.h"

namespace teejet::dds {

using namespace eprosima::fastdds::dds;
using eprosima::fastrtps::rtps::GuidPrefix_t;
using eprosima::fastrtps::rtps::iHandle2GUID;

PeerGateways::PeerGateways(Participant& participant, std::string own_name,
                           const eprosima::fastrtps::rtps::GUID_t& own_writer)
    : participant_(participant), own_name_(std::move(own_name)), own_writer_(own_writer) {}

Result<std::unique_ptr<PeerGateways>> PeerGateways::create(
    Participant& participant, std::string own_name,
    const eprosima::fastrtps::rtps::GUID_t& own_writer) {
  std::unique_ptr<PeerGateways> peers(
      new PeerGateways(participant, std::move(own_name), own_writer));
  auto topic = topics::topic_of<GatewayStatus>(participant);
  if (!topic) return topic.error();
  auto reader = participant.reader(*topic, topics::state_reader_qos(), peers.get(),
                                   StatusMask::data_available());
  if (!reader) return reader.error();
  peers->reader_ = *reader;
  return peers;
}

PeerGateways::~PeerGateways() { participant_.delete_reader(reader_); }

std::uint32_t PeerGateways::count() const {
  std::lock_guard lock(mutex_);
  std::set<std::string> names{own_name_};
  for (const auto& [instance, name] : alive_) names.insert(name);
  return static_cast<std::uint32_t>(names.size());
}

void PeerGateways::on_data_available(DataReader* reader) {
  // Taken before locking: Fast DDS holds the reader's lock while it calls the listener.
  std::vector<std::pair<GatewayStatus, SampleInfo>> taken;
  GatewayStatus status;
  SampleInfo info;
  while (reader->take_next_sample(&status, &info) == ReturnCode_t::RETCODE_OK) {
    taken.emplace_back(status, info);
  }
  std::vector<GuidPrefix_t> new_namesakes;
  {
    std::lock_guard lock(mutex_);
    for (const auto& [sample, sample_info] : taken) {
      if (!sample_info.valid_data) {
        // Its writers are gone (lease expired, or the gateway left): no longer heard.
        if (sample_info.instance_state != ALIVE_INSTANCE_STATE) {
          alive_.erase(sample_info.instance_handle);
        }
        continue;
      }
      alive_[sample_info.instance_handle] = sample.gateway().to_string();
      const auto writer = iHandle2GUID(sample_info.publication_handle);
      if (sample.gateway().to_string() == own_name_ && writer != own_writer_ &&
          namesakes_.insert(writer.guidPrefix).second) {
        new_namesakes.push_back(writer.guidPrefix);
      }
    }
  }
  for (const auto& prefix : new_namesakes) {
    spdlog::error(
        "another gateway on this domain is also called \"{}\" (participant {}): clients cannot "
        "tell the two apart and their valves appear under one name; give each gateway its own "
        "--name",
        own_name_, participant_text(prefix));
  }
}

}  // namespace teejet::dds
