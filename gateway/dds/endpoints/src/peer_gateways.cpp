#include "teejet/dds/peer_gateways.hpp"

#include <spdlog/spdlog.h>

#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <vector>

#include "teejet/codec/codec.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/valvePubSubTypes.h"

namespace teejet::dds {

using namespace eprosima::fastdds::dds;
using eprosima::fastrtps::rtps::GUID_t;
using eprosima::fastrtps::rtps::GuidPrefix_t;
using eprosima::fastrtps::rtps::iHandle2GUID;
using eprosima::fastrtps::rtps::InstanceHandle_t;

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
  // A writer that left (or whose participant's lease expired: killed, cut off) takes its
  // serials with it, although the instance (the name) may live on in a namesake. Not a lapse of
  // its liveliness alone: on a loaded machine that comes and goes, and the count with it.
  auto reader =
      participant.reader(*topic, topics::state_reader_qos(), peers.get(),
                         StatusMask::data_available() << StatusMask::subscription_matched());
  if (!reader) return reader.error();
  peers->reader_ = *reader;
  return peers;
}

PeerGateways::~PeerGateways() { participant_.delete_reader(reader_); }

std::uint32_t PeerGateways::count() const {
  std::lock_guard lock(mutex_);
  std::set<std::string> names{own_name_};
  for (const auto& [writer, other] : others_) names.insert(other.name);
  return static_cast<std::uint32_t>(names.size());
}

std::vector<std::string> PeerGateways::reporting_online(std::uint32_t serial) const {
  std::lock_guard lock(mutex_);
  std::vector<std::string> names;
  for (const auto& [writer, other] : others_) {
    if (other.online.contains(serial)) names.push_back(other.name);
  }
  return names;
}

std::set<PeerGateways::Shared> PeerGateways::shared_serials() const {
  std::set<Shared> shared;
  for (const auto& [writer, other] : others_) {
    for (const auto serial : other.online) {
      if (own_online_.contains(serial)) shared.insert({serial, other.name, writer.guidPrefix});
    }
  }
  return shared;
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
          // Captured by name: clang before 16 cannot capture a structured binding.
          std::erase_if(others_, [&gone = sample_info.instance_handle](const auto& other) {
            return other.second.instance == gone;
          });
        }
        continue;
      }
      const auto writer = iHandle2GUID(sample_info.publication_handle);
      const std::set<std::uint32_t> online(sample.serials_online().begin(),
                                           sample.serials_online().end());
      if (writer == own_writer_) {
        own_online_ = online;
        continue;
      }
      others_[writer] = Other{sample.gateway().to_string(), sample_info.instance_handle, online};
      if (sample.gateway().to_string() == own_name_ &&
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
  log_shared_serials();
}

void PeerGateways::on_subscription_matched(DataReader*, const SubscriptionMatchedStatus& status) {
  if (status.current_count_change < 0) forget_writer(status.last_publication_handle);
}

void PeerGateways::forget_writer(const InstanceHandle_t& writer) {
  {
    std::lock_guard lock(mutex_);
    others_.erase(iHandle2GUID(writer));
  }
  log_shared_serials();
}

void PeerGateways::log_shared_serials() {
  std::set<Shared> began;
  std::set<Shared> ended;
  {
    std::lock_guard lock(mutex_);
    const auto now = shared_serials();
    for (const auto& shared : now) {
      if (!logged_.contains(shared)) began.insert(shared);
    }
    for (const auto& shared : logged_) {
      if (!now.contains(shared)) ended.insert(shared);
    }
    logged_ = now;
  }
  for (const auto& shared : began) {
    spdlog::error(
        "valve {} is online on this gateway's bus and on gateway \"{}\"'s (participant {}): two "
        "valves carry this serial, or something replays it; commands to it but Stop are refused "
        "until "
        "only one gateway reports it",
        codec::format_serial(shared.serial), shared.other, participant_text(shared.participant));
  }
  for (const auto& shared : ended) {
    spdlog::warn(
        "valve {} is no longer reported online by gateway \"{}\": its commands are taken "
        "again",
        codec::format_serial(shared.serial), shared.other);
  }
}

}  // namespace teejet::dds
