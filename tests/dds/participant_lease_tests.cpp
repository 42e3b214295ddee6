// The participant lease a peer hears, as Fast DDS announces it in discovery, inside a private
// network namespace with the loopback profile (3 s lease): a participant made with a minimum
// lease announces at least that, one without announces the profile's, and valvectl announces
// one that outlasts its run; short-lived clients sit beyond the profile's initial peers and meet
// the programs that stay, not each other (docs/topics.md, "Short-lived participants").

#include <fastdds/rtps/common/PortParameters.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <cstdint>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "support/eventually.hpp"
#include "support/subprocess.hpp"
#include "support/test_domain.hpp"
#include "teejet/dds/participant.hpp"

namespace teejet::dds {
namespace {

using namespace std::chrono_literals;
using eprosima::fastdds::dds::DomainParticipant;
using eprosima::fastdds::dds::DomainParticipantFactory;
using teejet::testing::eventually;
using teejet::testing::Subprocess;
using teejet::testing::test_domain;

constexpr auto kMeetingDeadline = 10s;

// A bare Fast DDS participant that writes down the lease and discovery port each peer
// announces, by peer name.
class LeaseObserver final : public eprosima::fastdds::dds::DomainParticipantListener {
 public:
  explicit LeaseObserver(int domain) {
    auto* factory = DomainParticipantFactory::get_instance();
    participant_ =
        factory->create_participant(static_cast<eprosima::fastdds::dds::DomainId_t>(domain),
                                    factory->get_default_participant_qos(), this);
  }
  ~LeaseObserver() override {
    if (participant_ != nullptr)
      DomainParticipantFactory::get_instance()->delete_participant(participant_);
  }
  LeaseObserver(const LeaseObserver&) = delete;
  LeaseObserver& operator=(const LeaseObserver&) = delete;

  bool made() const { return participant_ != nullptr; }

  void on_participant_discovery(
      DomainParticipant*, eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) override {
    if (info.status != eprosima::fastrtps::rtps::ParticipantDiscoveryInfo::DISCOVERED_PARTICIPANT) {
      return;
    }
    Heard heard{.lease = info.info.m_leaseDuration, .discovery_port = 0};
    if (!info.info.metatraffic_locators.unicast.empty()) {
      heard.discovery_port = info.info.metatraffic_locators.unicast.front().port;
    }
    std::lock_guard lock(mutex_);
    heard_[info.info.m_participantName.to_string()] = heard;
  }

  // What a peer announced in discovery.
  struct Heard {
    eprosima::fastrtps::Duration_t lease;
    std::uint32_t discovery_port;  // of its discovery (metatraffic unicast) traffic; 0: none
  };
  // What the peer called `name` announced, once it was met within the deadline.
  std::optional<Heard> heard_from(const std::string& name) {
    std::optional<Heard> found;
    eventually(
        [&] {
          std::lock_guard lock(mutex_);
          if (auto it = heard_.find(name); it != heard_.end()) found = it->second;
          return found.has_value();
        },
        kMeetingDeadline);
    return found;
  }
  std::optional<eprosima::fastrtps::Duration_t> lease_of(const std::string& name) {
    const auto heard = heard_from(name);
    return heard ? std::optional(heard->lease) : std::nullopt;
  }
  std::optional<std::uint32_t> discovery_port_of(const std::string& name) {
    const auto heard = heard_from(name);
    return heard ? std::optional(heard->discovery_port) : std::nullopt;
  }

 private:
  DomainParticipant* participant_ = nullptr;
  std::mutex mutex_;
  std::map<std::string, Heard> heard_;
};

TEST(ParticipantLease, AMinimumLeaseIsAnnouncedAboveTheProfilesAndNoneKeepsTheProfiles) {
  LeaseObserver observer(test_domain());
  ASSERT_TRUE(observer.made());
  auto short_lived =
      Participant::create({.domain = test_domain(), .name = "short-lived", .minimum_lease = 30s});
  ASSERT_TRUE(short_lived) << short_lived.error().reason;
  auto long_lived = Participant::create({.domain = test_domain(), .name = "long-lived"});
  ASSERT_TRUE(long_lived) << long_lived.error().reason;
  // Below the profile's, the profile's stands.
  auto below = Participant::create(
      {.domain = test_domain(), .name = "below-the-profile", .minimum_lease = 1s});
  ASSERT_TRUE(below) << below.error().reason;

  const auto announced = observer.lease_of("short-lived");
  ASSERT_TRUE(announced) << "the participant with a minimum lease was not met";
  EXPECT_EQ(announced->seconds, 30);
  EXPECT_EQ(announced->nanosec, 0u);
  // config/fastdds-loopback.xml, which tests/netns/isolated gives every test.
  const auto profiles = observer.lease_of("long-lived");
  ASSERT_TRUE(profiles) << "the participant without a minimum lease was not met";
  EXPECT_EQ(profiles->seconds, 3);
  const auto kept = observer.lease_of("below-the-profile");
  ASSERT_TRUE(kept) << "the participant asking for less than the profile was not met";
  EXPECT_EQ(kept->seconds, 3);
}

std::chrono::nanoseconds announcement_period(const Participant& participant) {
  return from_dds_duration(participant.get()
                               ->get_qos()
                               .wire_protocol()
                               .builtin.discovery_config.leaseDuration_announcementperiod);
}

// A short-lived client announces itself less often than the profile's 250 ms; one that asks for
// less than the profile, or for as much as its lease, keeps the profile's.
TEST(ParticipantLease, ALeastAnnouncementPeriodSlowsOnlyTheParticipantThatAsksForIt) {
  auto quiet = Participant::create({.domain = test_domain(),
                                    .name = "quiet",
                                    .minimum_lease = 30s,
                                    .least_announcement_period = 2s});
  ASSERT_TRUE(quiet) << quiet.error().reason;
  auto plain = Participant::create({.domain = test_domain(), .name = "plain"});
  ASSERT_TRUE(plain) << plain.error().reason;
  auto below = Participant::create(
      {.domain = test_domain(), .name = "below", .least_announcement_period = 100ms});
  ASSERT_TRUE(below) << below.error().reason;
  auto beyond_its_lease = Participant::create(
      {.domain = test_domain(), .name = "beyond", .least_announcement_period = 3s});
  ASSERT_TRUE(beyond_its_lease) << beyond_its_lease.error().reason;

  EXPECT_EQ(announcement_period(**quiet), 2s);
  // config/fastdds-loopback.xml: every 250 ms, a lease of 3 s.
  EXPECT_EQ(announcement_period(**plain), 250ms);
  EXPECT_EQ(announcement_period(**below), 250ms);
  EXPECT_EQ(announcement_period(**beyond_its_lease), 250ms);
}

// The lease valvectl announces, as a peer hears it, for `arguments` against a domain without a
// gateway (so that the run lasts until it is interrupted).
std::optional<eprosima::fastrtps::Duration_t> valvectl_lease(
    const std::vector<std::string>& arguments) {
  LeaseObserver observer(test_domain());
  EXPECT_TRUE(observer.made());
  std::vector<std::string> argv = {VALVECTL_PATH, "--domain", std::to_string(test_domain())};
  argv.insert(argv.end(), arguments.begin(), arguments.end());
  Subprocess valvectl(argv);
  auto announced = observer.lease_of("valvectl");
  valvectl.signal(SIGINT);
  valvectl.wait(20s);
  return announced;
}

TEST(ParticipantLease, ValvectlAnnouncesThirtySecondsOrTenMoreThanItsRunMayLast) {
  const auto listing = valvectl_lease({"--timeout", "20", "list"});
  ASSERT_TRUE(listing) << "valvectl's participant was not met";
  EXPECT_EQ(listing->seconds, 30);
  // --timeout 30 each to find the valve, for its gateway's reader, for the first status and for
  // the readers' acknowledgements, then up to 60 s for the final one: 180 s, and 10 more.
  const auto waiting = valvectl_lease(
      {"--timeout", "30", "move", "TJV000001", "--to", "10", "--wait", "--wait-timeout", "60"});
  ASSERT_TRUE(waiting) << "valvectl's participant was not met";
  EXPECT_EQ(waiting->seconds, 190);
}

// The discovery (metatraffic unicast) port of participant id `id` in `domain`, by the RTPS
// port formula with Fast DDS's default parameters.
std::uint32_t discovery_port(int domain, int id) {
  const eprosima::fastrtps::rtps::PortParameters ports;
  return ports.portBase + ports.domainIDGain * static_cast<std::uint32_t>(domain) + ports.offsetd1 +
         ports.participantIDGain * static_cast<std::uint32_t>(id);
}

// config/fastdds-loopback.xml announces to participant ids 0-31 on 127.0.0.1.
constexpr int kLoopbackInitialPeers = 32;

TEST(ParticipantRange, ShortLivedClientsMeetTheProgramsThatStayAndNotEachOther) {
  LeaseObserver stays(test_domain());
  ASSERT_TRUE(stays.made());
  auto one = Participant::create(
      {.domain = test_domain(), .name = "client-one", .outside_initial_peers = true});
  ASSERT_TRUE(one) << one.error().reason;
  auto two = Participant::create(
      {.domain = test_domain(), .name = "client-two", .outside_initial_peers = true});
  ASSERT_TRUE(two) << two.error().reason;

  const auto beyond = discovery_port(test_domain(), kLoopbackInitialPeers);
  const auto one_port = stays.discovery_port_of("client-one");
  ASSERT_TRUE(one_port) << "the program that stays did not meet the first client";
  EXPECT_GE(*one_port, beyond);
  const auto two_port = stays.discovery_port_of("client-two");
  ASSERT_TRUE(two_port) << "the program that stays did not meet the second client";
  EXPECT_GE(*two_port, beyond);
  EXPECT_NE(*one_port, *two_port);
  ASSERT_TRUE(
      eventually([&] { return (*one)->participants_met() >= 1 && (*two)->participants_met() >= 1; },
                 kMeetingDeadline))
      << "a client did not meet the program that stays";
  EXPECT_EQ((*one)->participants_met(), 1u);
  EXPECT_EQ((*two)->participants_met(), 1u);
}

// A gateway that starts while valvectl runs does not hear its first announcements: it meets
// it at valvectl's next periodic one (every 2 s), and valvectl meets it then.
TEST(ParticipantRange, AProgramStartedAfterAShortLivedClientMeetsIt) {
  auto client = Participant::create({.domain = test_domain(),
                                     .name = "client",
                                     .minimum_lease = 30s,
                                     .least_announcement_period = 2s,
                                     .outside_initial_peers = true});
  ASSERT_TRUE(client) << client.error().reason;
  // Past Fast DDS's five initial announcements, 100 ms apart, which do reach the range.
  std::this_thread::sleep_for(700ms);
  auto later = Participant::create({.domain = test_domain(), .name = "started-later"});
  ASSERT_TRUE(later) << later.error().reason;
  EXPECT_TRUE(eventually(
      [&] { return (*client)->participants_met() == 1 && (*later)->participants_met() == 1; },
      kMeetingDeadline))
      << "met: client " << (*client)->participants_met() << ", started later "
      << (*later)->participants_met();
}

}  // namespace
}  // namespace teejet::dds
