#pragma once

// One DomainParticipant with one publisher and one subscriber, set up as in eProsima's examples
// (factory -> participant -> register type -> topic -> writer/reader) and torn down in reverse.
// Shared by the gateway, valvectl, the benchmarks and the tests. Nothing here throws: whatever
// the middleware refuses comes back as an Error (ErrorCode::kDds) naming what was refused.
// The first participant of a process sends Fast DDS's own log lines to stderr (stdout carries
// the programs' data).

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/ContentFilteredTopic.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <string_view>

#include "teejet/core/result.hpp"

namespace teejet::dds {

// The highest domain id: with the default port parameters, the RTPS port formula's limit.
inline constexpr int kMaxDomain = 232;

struct ParticipantOptions {
  int domain = 0;
  std::string profile_file;  // Fast DDS XML profiles, loaded before any default QoS is read
  std::string name = "teejet";
  // What this participant is to the others ("gateway"), announced with it in discovery
  // (participant property teejet.role), so that a client that met a gateway's participant
  // waits for its topics instead of judging the domain without it. Empty: none announced.
  std::string role;
  // Called with a remote participant's GUID prefix ("01.0f.…") when its lease expired: the
  // process died or became unreachable. A participant that leaves in order is not reported.
  // Runs on a Fast DDS thread: hand the news to a thread of your own.
  std::function<void(const std::string& guid_prefix)> on_participant_dropped;
  // The least lease this participant announces (how long the others keep it after it falls
  // silent), whatever the profile says; zero: the profile's. For a short-lived participant:
  // Fast DDS 2.9.1 aborts in PDP.cpp:1140 when a participant that leaves in order is removed
  // while a peer's lease check for it runs, and a peer checks once per lease (docs/topics.md,
  // "Short-lived participants").
  std::chrono::seconds minimum_lease{0};
  // The least period of this participant's periodic announcements, whatever the profile says
  // (below its lease); zero: the profile's. Discovery does not wait for them: a participant
  // meets the others through its initial announcements (Fast DDS: five, 100 ms apart) and by
  // answering theirs, so they only keep its lease. A client that announces a long lease need not
  // announce four times a second to every participant of the domain (the loopback profile):
  // two hundred at once would keep every CPU busy with announcements.
  std::chrono::milliseconds least_announcement_period{0};
  // Take the ports of a participant id beyond those the profile's initial peers name (Fast DDS
  // announces to ids 0 up to the UDP transport's maxInitialPeersRange on each initial peer
  // without a port: 0-31 in the loopback profile). The programs that stay take the lowest free
  // ids, inside that range, and answer this participant's announcements; other participants
  // beyond the range never hear it, nor it them. For short-lived clients (valvectl): two hundred
  // of them at once then meet only the programs that stay, not every other client as well, and
  // they leave the ids in the range free for a gateway that starts while they run. Has no effect
  // with multicast discovery, a discovery server, initial peers with explicit ports, or a profile
  // that sets the participant id.
  bool outside_initial_peers = false;
};

// A timeout as Fast DDS's waits take it: below zero is zero, beyond Duration_t's seconds its
// largest.
inline eprosima::fastrtps::Duration_t to_dds_duration(std::chrono::nanoseconds timeout) {
  const auto left = std::max(timeout, std::chrono::nanoseconds::zero());
  const auto whole = std::chrono::duration_cast<std::chrono::seconds>(left);
  return {static_cast<std::int32_t>(std::min<std::int64_t>(whole.count(), 0x7FFFFFFF)),
          static_cast<std::uint32_t>((left - whole).count())};
}

// A Fast DDS duration (a lease, an announcement period) as nanoseconds.
inline std::chrono::nanoseconds from_dds_duration(const eprosima::fastrtps::Duration_t& duration) {
  return std::chrono::seconds(duration.seconds) + std::chrono::nanoseconds(duration.nanosec);
}

// Nanoseconds since the Unix epoch as a DDS timestamp (the source timestamp of a write);
// beyond Time_t's seconds its largest.
inline eprosima::fastrtps::Time_t to_dds_time(std::uint64_t unix_ns) {
  constexpr std::uint64_t kSecond = 1'000'000'000;
  return {static_cast<std::int32_t>(std::min<std::uint64_t>(unix_ns / kSecond, 0x7FFFFFFF)),
          static_cast<std::uint32_t>(unix_ns % kSecond)};
}

// The participant an endpoint belongs to, as its GUID prefix ("01.0f.…"): of a sample's
// publication_handle or a matched reader or writer. A gateway's writers and readers all share it.
std::string participant_of(const eprosima::fastrtps::rtps::InstanceHandle_t& endpoint);
std::string participant_text(const eprosima::fastrtps::rtps::GuidPrefix_t& prefix);

// A fastddsgen type whose keys are computed one at a time. fastddsgen 2.3's getKey() serializes
// the key into a buffer of the type object and hashes it with an MD5 member, and a participant
// has one type object per type for every writer and reader of its topic: a gateway publishing
// its locations while its reader of the other gateways' locations filed one raced there (TSan,
// CI), and two receive threads (shared memory and UDP) can race the same way, giving an instance
// a wrong key.
template <class PubSubType>
class KeyLockedType final : public PubSubType {
 public:
  bool getKey(void* data, eprosima::fastrtps::rtps::InstanceHandle_t* handle,
              bool force_md5) override {
    std::lock_guard lock(key_mutex_);
    return PubSubType::getKey(data, handle, force_md5);
  }

 private:
  std::mutex key_mutex_;
};

// The participant property that carries ParticipantOptions::role.
inline constexpr const char* kRoleProperty = "teejet.role";
inline constexpr const char* kGatewayRole = "gateway";

class Participant {
 public:
  static Result<std::unique_ptr<Participant>> create(const ParticipantOptions& options);
  // The remote participants discovery found, alive and announcing `role`, as GUID prefixes.
  std::set<std::string> participants_with_role(std::string_view role) const;
  // How many remote participants discovery has found alive, whatever their role.
  std::size_t participants_met() const;
  // Whether every participant already running has had the time to be met: two of the profile's
  // announcement periods (at most 1 s) since this one was made. A participant already running may
  // answer a newcomer only at its next periodic announcement (the loopback profile's 250 ms), so
  // until then the participants met so far need not be all there are. Participants met later
  // (started after this one, or whose announcements were lost) do not extend it; a gateway
  // among them is counted by participants_with_role and waited for all the same.
  bool discovery_settled() const;
  // Whether the profile gives it a TCP transport (Fast DDS 2.9.1's has defects of its own:
  // docs/remote-benches.md).
  bool uses_tcp() const { return uses_tcp_; }
  // How DDS is set up, for the logs: "profile FILE (from --profile)" or "Fast DDS's defaults
  // (no profile)", then "DDS-Security on (…)" or "DDS-Security off".
  const std::string& setup() const { return setup_; }
  ~Participant();  // deletes every entity made here, then the participant
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  // The topic of `name`, registering the type on first use. PubSubType is a fastddsgen
  // <Type>PubSubType.
  template <class PubSubType>
  Result<eprosima::fastdds::dds::Topic*> topic(const std::string& name) {
    return topic(name, eprosima::fastdds::dds::TypeSupport(new KeyLockedType<PubSubType>()));
  }

  Result<eprosima::fastdds::dds::DataWriter*> writer(
      eprosima::fastdds::dds::Topic* topic, const eprosima::fastdds::dds::DataWriterQos& qos,
      eprosima::fastdds::dds::DataWriterListener* listener = nullptr);
  // A listener hears only what `mask` names: data available and liveliness changed unless told
  // otherwise (a wider mask would take callbacks other parts rely on).
  // `topic`: a Topic, or a filtered one (reader_of_serials).
  Result<eprosima::fastdds::dds::DataReader*> reader(
      eprosima::fastdds::dds::TopicDescription* topic,
      const eprosima::fastdds::dds::DataReaderQos& qos,
      eprosima::fastdds::dds::DataReaderListener* listener = nullptr,
      const eprosima::fastdds::dds::StatusMask& mask =
          eprosima::fastdds::dds::StatusMask::data_available()
          << eprosima::fastdds::dds::StatusMask::liveliness_changed());
  // A reader of `topic` that keeps the samples of `serials` only (dds/serial_filter.hpp).
  Result<eprosima::fastdds::dds::DataReader*> reader_of_serials(
      eprosima::fastdds::dds::Topic* topic, const std::set<std::uint32_t>& serials,
      const eprosima::fastdds::dds::DataReaderQos& qos);

  // Delete a reader or writer made here (nullptr: nothing); after delete_reader returns no
  // callback reaches its listener.
  void delete_reader(eprosima::fastdds::dds::DataReader* reader);
  // How many readers of `topic_name` this participant has.
  std::size_t readers_of(const std::string& topic_name) const;
  void delete_writer(eprosima::fastdds::dds::DataWriter* writer);

  eprosima::fastdds::dds::DomainParticipant* get() const { return participant_; }

 private:
  Participant() = default;
  Result<eprosima::fastdds::dds::Topic*> topic(const std::string& name,
                                               eprosima::fastdds::dds::TypeSupport type);

  class DiscoveryListener;
  std::unique_ptr<DiscoveryListener> discovery_listener_;
  eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
  eprosima::fastdds::dds::Publisher* publisher_ = nullptr;
  eprosima::fastdds::dds::Subscriber* subscriber_ = nullptr;
  std::map<std::string, eprosima::fastdds::dds::Topic*> topics_;
  std::map<std::string, eprosima::fastdds::dds::ContentFilteredTopic*> filtered_topics_;
  std::string setup_;
  bool uses_tcp_ = false;
  std::chrono::steady_clock::time_point created_ = std::chrono::steady_clock::now();
  // The others' announcement period, as the profile gives it (this one's may be longer).
  std::chrono::nanoseconds profile_announcement_{0};
};

}  // namespace teejet::dds
