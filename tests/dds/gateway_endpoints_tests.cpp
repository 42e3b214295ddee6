// The gateway's DDS endpoints against independent readers and writers, inside a private network
// namespace (see tests/netns/isolated).

#include <gtest/gtest.h>
#include <signal.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <functional>
#include <mutex>

#include "support/eventually.hpp"
#include "support/subprocess.hpp"
#include "teejet/dds/gateway_endpoints.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/valvePubSubTypes.h"

namespace teejet::dds {
namespace {

using namespace std::chrono_literals;
using eprosima::fastdds::dds::DataReader;
using eprosima::fastdds::dds::SampleInfo;
using ReturnCode = eprosima::fastrtps::types::ReturnCode_t;

using teejet::testing::eventually;
using teejet::testing::Subprocess;

int test_domain() {
  // Shared memory is not separated by network namespaces: each test binary keeps to its own
  // range of domains (dds 10-99, gateway 100-199, valvectl 200-231).
  return 10 + static_cast<int>(::getpid() % 90);
}

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

class GatewayEndpointsTest : public ::testing::Test {
 protected:
  Participant gateway{{.domain = test_domain(), .name = "gateway-under-test"}};
  GatewayPublisher publisher{gateway};
};

TEST_F(GatewayEndpointsTest, LateJoinerSeesEveryValvePresenceAtOnce) {
  publisher.presence(presence(1, 0xD8));
  publisher.presence(presence(2, 0xD9));
  publisher.presence(presence(3, 0xDA));
  publisher.presence(presence(1, 0xDB));  // KEEP_LAST 1: only the newest per valve

  Participant late{{.domain = test_domain(), .name = "late-ecu"}};
  auto* reader = late.reader(late.topic<ValvePresencePubSubType>(topics::kPresence),
                             topics::state_reader_qos());
  std::map<std::uint32_t, std::uint8_t> seen;
  ASSERT_TRUE(eventually(
      [&] {
        for (auto& [sample, info] : take_all<ValvePresence>(reader)) {
          if (info.valid_data) seen[sample.serial()] = sample.address();
        }
        return seen.size() == 3;
      },
      10s));
  EXPECT_EQ(seen[1], 0xDB);
  EXPECT_EQ(seen[2], 0xD9);
}

TEST_F(GatewayEndpointsTest, TelemetryCarriesTheCanReceiveTimeAsSourceTimestamp) {
  Participant ecu{{.domain = test_domain(), .name = "ecu"}};
  auto* reader =
      ecu.reader(ecu.topic<ValvePositionPubSubType>(topics::kPosition), topics::state_reader_qos());
  ValvePosition position;
  position.serial(4711);
  position.degrees(42.5f);
  position.received_ns(1'700'000'000'123'456'789);
  ASSERT_TRUE(eventually(
      [&] {
        publisher.telemetry(position);
        return reader->get_unread_count() > 0;
      },
      10s));
  auto samples = take_all<ValvePosition>(reader);
  ASSERT_FALSE(samples.empty());
  EXPECT_FLOAT_EQ(samples[0].first.degrees(), 42.5f);
  EXPECT_EQ(samples[0].second.source_timestamp.seconds(), 1'700'000'000);
  EXPECT_EQ(samples[0].second.source_timestamp.nanosec(), 123'456'789u);
}

TEST_F(GatewayEndpointsTest, ClearedErrorsAreDisposed) {
  Participant ecu{{.domain = test_domain(), .name = "ecu"}};
  auto* reader =
      ecu.reader(ecu.topic<ValveErrorPubSubType>(topics::kError), topics::state_reader_qos());
  ValveError error;
  error.serial(9);
  error.kind(ERROR_HIGH_VOLTAGE);
  error.value(17.2f);
  error.limit(16.5f);
  publisher.telemetry(error);
  ASSERT_TRUE(eventually([&] { return reader->get_unread_count() > 0; }, 10s));
  (void)take_all<ValveError>(reader);
  publisher.error_cleared(9, ERROR_HIGH_VOLTAGE);
  bool disposed = false;
  ASSERT_TRUE(eventually(
      [&] {
        for (auto& [sample, info] : take_all<ValveError>(reader)) {
          disposed |=
              info.instance_state == eprosima::fastdds::dds::NOT_ALIVE_DISPOSED_INSTANCE_STATE;
        }
        return disposed;
      },
      10s));
}

struct CommandLog {
  std::mutex mutex;
  std::condition_variable changed;
  std::vector<std::uint32_t> ids;
  std::vector<std::string> writers;
  std::vector<std::string> lost;

  bool wait(const std::function<bool()>& condition, std::chrono::milliseconds deadline) {
    std::unique_lock lock(mutex);
    return changed.wait_for(lock, deadline, condition);
  }
};

TEST_F(GatewayEndpointsTest, EveryCommandArrivesInOrderWithItsWriter) {
  CommandLog log;
  CommandSubscription subscription(
      gateway,
      [&](const ValveCommand& command, const std::string& writer) {
        std::lock_guard lock(log.mutex);
        log.ids.push_back(command.command_id());
        log.writers.push_back(writer);
        log.changed.notify_all();
      },
      [](const std::string&) {});

  Participant ecu{{.domain = test_domain(), .name = "ecu"}};
  auto* writer =
      ecu.writer(ecu.topic<ValveCommandPubSubType>(topics::kCommand), topics::command_writer_qos());
  ASSERT_TRUE(eventually(
      [&] {
        eprosima::fastdds::dds::PublicationMatchedStatus matched;
        writer->get_publication_matched_status(matched);
        return matched.current_count > 0;
      },
      10s));
  for (std::uint32_t id = 1; id <= 200; ++id) {
    ValveCommand command;
    command.serial(1);  // one instance: KEEP_LAST would drop, KEEP_ALL must not
    command.command_id(id);
    command.kind(COMMAND_STOP);
    ASSERT_EQ(writer->write(&command), true);
  }
  ASSERT_TRUE(log.wait([&] { return log.ids.size() >= 200; }, 10s)) << log.ids.size();
  std::lock_guard lock(log.mutex);
  for (std::uint32_t i = 0; i < 200; ++i) ASSERT_EQ(log.ids[i], i + 1);
  EXPECT_EQ(log.writers.front(), log.writers.back());
  EXPECT_FALSE(log.writers.front().empty());
}

TEST_F(GatewayEndpointsTest, AKilledCommanderIsReportedLostForTheFailSafe) {
  CommandLog log;
  CommandSubscription subscription(
      gateway,
      [&](const ValveCommand&, const std::string& writer) {
        std::lock_guard lock(log.mutex);
        log.writers.push_back(writer);
        log.changed.notify_all();
      },
      [&](const std::string& writer) {
        std::lock_guard lock(log.mutex);
        log.lost.push_back(writer);
        log.changed.notify_all();
      });

  Subprocess commander({COMMAND_WRITER_PATH, std::to_string(test_domain()), "77"});
  ASSERT_TRUE(log.wait([&] { return !log.writers.empty(); }, 20s)) << "no command arrived";
  const auto killed_at = std::chrono::steady_clock::now();
  commander.signal(SIGKILL);
  commander.wait(commander.elapsed() + 10s);  // reaps it

  ASSERT_TRUE(log.wait([&] { return !log.lost.empty(); }, 10s)) << "liveliness loss not seen";
  const auto noticed_after = std::chrono::steady_clock::now() - killed_at;
  std::lock_guard lock(log.mutex);
  EXPECT_EQ(log.lost.front(), log.writers.front());
  std::printf("commander loss noticed %lld ms after SIGKILL\n",
              static_cast<long long>(
                  std::chrono::duration_cast<std::chrono::milliseconds>(noticed_after).count()));
}

}  // namespace
}  // namespace teejet::dds
