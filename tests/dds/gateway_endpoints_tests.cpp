// The gateway's DDS endpoints against independent readers and writers, inside a private network
// namespace (see tests/netns/isolated).

#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/log/Log.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <filesystem>
#include <fstream>
#include <mutex>

#include "support/dds_peer.hpp"
#include "support/eventually.hpp"
#include "support/subprocess.hpp"
#include "support/test_domain.hpp"
#include "support/valve_commands.hpp"
#include "teejet/dds/command_subscription.hpp"
#include "teejet/dds/gateway_publisher.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/valvePubSubTypes.h"

namespace teejet::dds {
namespace {

using namespace std::chrono_literals;
using eprosima::fastdds::dds::DataReader;
using eprosima::fastdds::dds::DataWriter;
using eprosima::fastdds::dds::SampleInfo;
using ReturnCode = eprosima::fastrtps::types::ReturnCode_t;

using teejet::testing::DdsPeer;
using teejet::testing::eventually;
using teejet::testing::from;
using teejet::testing::stop;
using teejet::testing::Subprocess;
using teejet::testing::test_domain;

// How long a test waits for what it expects before it fails.
constexpr auto kDeadline = 10s;

ValvePresence presence(std::uint32_t serial, std::uint8_t address) {
  ValvePresence p;
  p.serial(serial);
  p.address(address);
  p.online(true);
  p.last_seen_ns(1'700'000'000'000'000'000);
  p.gateway("gw");
  return p;
}

template <class Sample>
std::vector<std::pair<Sample, SampleInfo>> take_all(DataReader* reader) {
  std::vector<std::pair<Sample, SampleInfo>> out;
  Sample sample;
  SampleInfo info;
  while (reader->take_next_sample(&sample, &info) == ReturnCode::RETCODE_OK) {
    out.emplace_back(sample, info);
  }
  return out;
}

// True once `writer` matched a reader (the gateway's) within `deadline`.
bool matched_within(DataWriter* writer, std::chrono::milliseconds deadline) {
  return eventually(
      [&] {
        eprosima::fastdds::dds::PublicationMatchedStatus status;
        writer->get_publication_matched_status(status);
        return status.current_count > 0;
      },
      deadline);
}

// A command writer of an ECU, matched with the gateway's reader.
DataWriter* command_writer(DdsPeer& ecu) {
  auto topic = ecu.participant().topic<ValveCommandPubSubType>(topics::kCommand);
  auto writer = ecu.participant().writer(*topic, topics::command_writer_qos());
  if (!writer) return nullptr;
  return matched_within(*writer, kDeadline) ? *writer : nullptr;
}

class GatewayEndpointsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto participant = Participant::create({.domain = test_domain(), .name = "gateway-under-test"});
    ASSERT_TRUE(participant) << participant.error().reason;
    gateway = std::move(*participant);
    auto made = GatewayPublisher::create(*gateway, "gateway-under-test");
    ASSERT_TRUE(made) << made.error().reason;
    publisher = std::move(*made);
  }

  std::unique_ptr<CommandSubscription> subscribe() {
    auto made = CommandSubscription::create(*gateway, lost);
    EXPECT_TRUE(made) << made.error().reason;
    return made ? std::move(*made) : nullptr;
  }

  // Waits (up to `deadline`) and takes until `enough` holds over everything taken so far.
  static CommandSubscription::Events collect(
      CommandSubscription& subscription,
      const std::function<bool(const CommandSubscription::Events&)>& enough,
      std::chrono::milliseconds deadline) {
    CommandSubscription::Events all;
    const auto until = std::chrono::steady_clock::now() + deadline;
    while (!enough(all) && std::chrono::steady_clock::now() < until) {
      auto events = subscription.wait(100ms);
      for (auto& c : events.commands) all.commands.push_back(std::move(c));
      for (auto& l : events.lost_commanders) all.lost_commanders.push_back(std::move(l));
    }
    return all;
  }

  std::unique_ptr<Participant> gateway;
  std::unique_ptr<GatewayPublisher> publisher;
  std::shared_ptr<LostCommanders> lost = std::make_shared<LostCommanders>();
};

// Fast DDS 2.9 ends the whole process for a domain its port formula cannot map; the participant
// refuses it first, so a bad --domain or configuration is an error, not a silent exit(1).
TEST(Participant, ADomainOutsideZeroTo232IsRefusedNotFatal) {
  for (const int domain : {-1, 233, 1000}) {
    const auto refused = Participant::create({.domain = domain});
    ASSERT_FALSE(refused) << domain;
    EXPECT_EQ(refused.error().code, ErrorCode::kOutOfRange);
    EXPECT_EQ(refused.error().reason,
              "DDS domain " + std::to_string(domain) + " is outside 0 to 232");
  }
}

// The programs' stdout carries data (valvectl --json): Fast DDS's own complaints go to stderr.
TEST(Participant, FastDdsLogLinesGoToStderrNotStdout) {
  ::testing::internal::CaptureStdout();
  ::testing::internal::CaptureStderr();
  const auto refused =
      Participant::create({.domain = test_domain(), .profile_file = "/nonexistent/profile.xml"});
  eprosima::fastdds::dds::Log::Flush();
  const std::string out = ::testing::internal::GetCapturedStdout();
  const std::string err = ::testing::internal::GetCapturedStderr();
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().reason,
            "cannot load Fast DDS profiles from '/nonexistent/profile.xml'");
  EXPECT_EQ(out, "");
  EXPECT_NE(err.find("/nonexistent/profile.xml"), std::string::npos) << err;
}

// A --profile whose names the environment's file already took would silently leave that
// file's settings in force (a secure profile then ran without security): it is refused instead.
TEST(Participant, AProfileClashingWithTheEnvironmentsIsRefusedNotIgnored) {
  const char* environment = std::getenv("FASTRTPS_DEFAULT_PROFILES_FILE");
  if (environment == nullptr) GTEST_SKIP() << "runs under tests/netns/isolated, which sets it";
  const std::string copy = ::testing::TempDir() + "clashing-profile.xml";
  {
    std::ifstream original(environment);
    std::ofstream out(copy);
    out << original.rdbuf();
  }
  const auto refused = Participant::create({.domain = test_domain(), .profile_file = copy});
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().reason,
            "Fast DDS refused part of the profiles in '" + copy +
                "': a profile or transport name in it is taken by a file loaded before it (" +
                std::filesystem::weakly_canonical(environment).string() +
                "), whose settings would apply instead; rename them, or leave "
                "FASTRTPS_DEFAULT_PROFILES_FILE unset");
  std::remove(copy.c_str());
}

// A client learns that a participant is a gateway from discovery alone, before any of its
// topics match, and forgets it when it leaves.
TEST(Participant, ARoleIsAnnouncedInDiscoveryAndForgottenWhenTheParticipantLeaves) {
  auto client = Participant::create({.domain = test_domain(), .name = "client"});
  auto gateway = Participant::create({.domain = test_domain(), .name = "gw", .role = kGatewayRole});
  auto other = Participant::create({.domain = test_domain(), .name = "other", .role = "recorder"});
  ASSERT_TRUE(client && gateway && other);
  const std::string gateway_prefix = participant_text((*gateway)->get()->guid().guidPrefix);
  const std::string other_prefix = participant_text((*other)->get()->guid().guidPrefix);
  ASSERT_TRUE(eventually(
      [&] {
        return (*client)->participants_with_role(kGatewayRole) ==
                   std::set<std::string>{gateway_prefix} &&
               (*client)->participants_with_role("recorder") == std::set<std::string>{other_prefix};
      },
      10s));
  gateway->reset();
  EXPECT_TRUE(
      eventually([&] { return (*client)->participants_with_role(kGatewayRole).empty(); }, 10s));
  EXPECT_EQ((*client)->participants_with_role("recorder"), std::set<std::string>{other_prefix});
}

TEST_F(GatewayEndpointsTest, LateJoinerSeesEveryValvePresenceAtOnce) {
  publisher->presence(presence(1, 0xD8));
  publisher->presence(presence(2, 0xD9));
  publisher->presence(presence(3, 0xDA));
  publisher->presence(presence(1, 0xDB));  // KEEP_LAST 1: only the newest per valve

  DdsPeer late(test_domain(), "late-ecu");
  auto* reader = late.reader<ValvePresence>();
  ASSERT_NE(reader, nullptr);
  std::map<std::uint32_t, std::uint8_t> seen;
  ASSERT_TRUE(eventually(
      [&] {
        for (auto& [sample, info] : take_all<ValvePresence>(reader)) {
          if (info.valid_data) seen[sample.serial()] = sample.address();
        }
        return seen.size() == 3;
      },
      kDeadline));
  EXPECT_EQ(seen[1], 0xDB);
  EXPECT_EQ(seen[2], 0xD9);
}

TEST_F(GatewayEndpointsTest, EveryTelemetryTypeReachesItsTopicWithTheCanReceiveTimeAsSource) {
  DdsPeer ecu(test_domain(), "ecu");
  auto* position = ecu.reader<ValvePosition>();
  auto* cycles = ecu.reader<ValveCycleCounts>();
  ASSERT_TRUE(position && cycles);
  ValvePosition sample;
  sample.serial(4711);
  sample.degrees(42.5f);
  sample.received_ns(1'700'000'000'123'456'789);
  ValveCycleCounts count;
  count.serial(4711);
  count.count(99);
  count.received_ns(1'700'000'000'000'000'001);
  // Written once: a late joiner gets it (state QoS).
  publisher->telemetry(sample);
  publisher->telemetry(count);
  ASSERT_TRUE(
      eventually([&] { return position->get_unread_count() > 0 && cycles->get_unread_count() > 0; },
                 kDeadline));
  auto positions = take_all<ValvePosition>(position);
  ASSERT_FALSE(positions.empty());
  EXPECT_FLOAT_EQ(positions[0].first.degrees(), 42.5f);
  EXPECT_EQ(positions[0].second.source_timestamp.seconds(), 1'700'000'000);
  EXPECT_EQ(positions[0].second.source_timestamp.nanosec(), 123'456'789u);
  EXPECT_EQ(take_all<ValveCycleCounts>(cycles).at(0).first.count(), 99u);
}

// A presence carries its valve's last I'm Here, which can be earlier than the sample before it
// (a valve that went offline): its source timestamp is then that sample's, never earlier
// (source_order_tests.cpp shows the abort it prevents), and last_seen_ns stays exact.
TEST_F(GatewayEndpointsTest, AStampEarlierThanTheWritersLastGoesOutAtItsStamp) {
  DdsPeer ecu(test_domain(), "ecu");
  auto* reader = ecu.reader<ValvePresence>();
  ASSERT_NE(reader, nullptr);
  constexpr std::uint64_t kBase = 1'700'000'000'000'000'000;
  auto heard = [](std::uint32_t serial, std::uint64_t last_seen_ns, bool online) {
    auto sample = presence(serial, static_cast<std::uint8_t>(0xD7 + serial));
    sample.last_seen_ns(last_seen_ns);
    sample.online(online);
    return sample;
  };
  publisher->presence(heard(1, kBase + 500, true));
  publisher->presence(heard(2, kBase + 100, false));
  publisher->presence(heard(3, kBase + 900, true));
  std::map<std::uint32_t, std::pair<std::uint64_t, std::uint64_t>> stamps;  // source, last seen
  ASSERT_TRUE(eventually(
      [&] {
        for (auto& [sample, info] : take_all<ValvePresence>(reader)) {
          stamps[sample.serial()] = {
              std::uint64_t(info.source_timestamp.seconds()) * 1'000'000'000 +
                  info.source_timestamp.nanosec(),
              sample.last_seen_ns()};
        }
        return stamps.size() == 3;
      },
      kDeadline));
  using Stamps = std::pair<std::uint64_t, std::uint64_t>;
  EXPECT_EQ(stamps[1], (Stamps{kBase + 500, kBase + 500}));
  EXPECT_EQ(stamps[2], (Stamps{kBase + 500, kBase + 100}));
  EXPECT_EQ(stamps[3], (Stamps{kBase + 900, kBase + 900}));
}

TEST_F(GatewayEndpointsTest, ClearedErrorsAreDisposed) {
  DdsPeer ecu(test_domain(), "ecu");
  auto* reader = ecu.reader<ValveError>();
  ASSERT_NE(reader, nullptr);
  ValveError error;
  error.serial(9);
  error.kind(ERROR_HIGH_VOLTAGE);
  error.value(17.2f);
  error.limit(16.5f);
  publisher->telemetry(error);
  ASSERT_TRUE(eventually([&] { return reader->get_unread_count() > 0; }, kDeadline));
  (void)take_all<ValveError>(reader);
  publisher->error_cleared(9, ERROR_HIGH_VOLTAGE);
  bool disposed = false;
  ASSERT_TRUE(eventually(
      [&] {
        for (auto& [sample, info] : take_all<ValveError>(reader)) {
          disposed |=
              info.instance_state == eprosima::fastdds::dds::NOT_ALIVE_DISPOSED_INSTANCE_STATE;
        }
        return disposed;
      },
      kDeadline));
}

TEST_F(GatewayEndpointsTest, EveryCommandArrivesInOrderWithItsWriter) {
  auto subscription = subscribe();
  ASSERT_NE(subscription, nullptr);
  DdsPeer ecu(test_domain(), "ecu");
  auto* writer = command_writer(ecu);
  ASSERT_NE(writer, nullptr);
  // All to valve 1: one instance, where KEEP_LAST would drop and KEEP_ALL must not.
  for (std::uint32_t id = 1; id <= 200; ++id) {
    auto command = from("ecu", id, stop(1));
    ASSERT_EQ(writer->write(&command), true);
  }
  const auto events = collect(
      *subscription, [](const auto& e) { return e.commands.size() >= 200; }, kDeadline);
  ASSERT_EQ(events.commands.size(), 200u);
  for (std::uint32_t i = 0; i < 200; ++i) ASSERT_EQ(events.commands[i].command.command_id(), i + 1);
  EXPECT_EQ(events.commands.front().writer, events.commands.back().writer);
  EXPECT_FALSE(events.commands.front().writer.empty());
}

TEST_F(GatewayEndpointsTest, AWaitEndsAtItsTimeoutOrWhenWoken) {
  auto subscription = subscribe();
  ASSERT_NE(subscription, nullptr);
  EXPECT_TRUE(subscription->wait(10ms).commands.empty());
  // A woken wait returns before its timeout: one that ran to it was not woken.
  subscription->wake();  // before the wait: it must not block then
  auto waited_from = std::chrono::steady_clock::now();
  EXPECT_TRUE(subscription->wait(kDeadline).commands.empty());
  EXPECT_LT(std::chrono::steady_clock::now() - waited_from, kDeadline)
      << "a wake() before the wait was lost";
  lost->report("01.02.03");
  waited_from = std::chrono::steady_clock::now();
  EXPECT_EQ(subscription->wait(kDeadline).lost_commanders, std::vector<std::string>{"01.02.03"});
  EXPECT_LT(std::chrono::steady_clock::now() - waited_from, kDeadline)
      << "a lost commander did not wake the wait";
}

// Issue 7, bug 5: the subscription registered as listener on a reader it did not own and never
// detached, so once it was destroyed Fast DDS called freed memory. Now it owns its reader and
// deletes it: a later command has nowhere to go, and nothing of the old subscription runs.
TEST_F(GatewayEndpointsTest, ADestroyedSubscriptionTakesItsReaderWithIt) {
  subscribe().reset();
  DdsPeer ecu(test_domain(), "ecu");
  auto topic = ecu.participant().topic<ValveCommandPubSubType>(topics::kCommand);
  auto writer = ecu.participant().writer(*topic, topics::command_writer_qos());
  ASSERT_TRUE(writer);
  // A reader that still existed would match within a discovery round; give it several.
  EXPECT_FALSE(matched_within(*writer, 2s));
  auto unheard = from("ecu", 1, stop(1));
  EXPECT_TRUE((*writer)->write(&unheard));

  // A new subscription works as the first did: the ECU's writer finds it, and the next command
  // arrives. Commands are VOLATILE: the one written while no subscription existed does not.
  auto again = subscribe();
  ASSERT_NE(again, nullptr);
  ASSERT_TRUE(matched_within(*writer, kDeadline)) << "the new subscription's reader never matched";
  auto next = from("ecu", 2, stop(1));
  ASSERT_TRUE((*writer)->write(&next));
  const auto events = collect(
      *again, [](const auto& e) { return !e.commands.empty(); }, kDeadline);
  ASSERT_EQ(events.commands.size(), 1u);
  EXPECT_EQ(events.commands[0].command.command_id(), 2u);
  EXPECT_EQ(events.commands[0].command.kind(), COMMAND_STOP);
  EXPECT_FALSE(events.commands[0].writer.empty());
}

TEST_F(GatewayEndpointsTest, AKilledCommanderIsReportedLostForTheFailSafe) {
  auto subscription = subscribe();
  ASSERT_NE(subscription, nullptr);
  Subprocess commander({COMMAND_WRITER_PATH, std::to_string(test_domain()), "77"});
  // The writer gives up, saying why, once no command reader matched it within 15 s.
  ASSERT_TRUE(commander.wait_for_stdout("sent", 2 * kDeadline)) << commander.err();
  const auto first = collect(
      *subscription, [](const auto& e) { return !e.commands.empty(); }, kDeadline);
  ASSERT_FALSE(first.commands.empty()) << "no command arrived";
  const auto killed_at = std::chrono::steady_clock::now();
  commander.signal(SIGKILL);
  commander.wait(commander.elapsed() + kDeadline);  // reaps it

  // Three lease periods idle; over 10 s once under ASan beside the ci stage's tests: the wait
  // is a deadline for a loss never reported, and what it takes is printed below.
  const auto lost_events = collect(
      *subscription, [](const auto& e) { return !e.lost_commanders.empty(); }, 3 * kDeadline);
  ASSERT_FALSE(lost_events.lost_commanders.empty()) << "liveliness loss not seen";
  const auto noticed_after = std::chrono::steady_clock::now() - killed_at;
  EXPECT_EQ(lost_events.lost_commanders.front(), first.commands.front().writer);
  std::printf("commander loss noticed %lld ms after SIGKILL\n",
              static_cast<long long>(
                  std::chrono::duration_cast<std::chrono::milliseconds>(noticed_after).count()));
}

}  // namespace
}  // namespace teejet::dds
