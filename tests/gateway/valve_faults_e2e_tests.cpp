// Valve faults through the whole gateway (bus, bridge, DDS), as an ECU sees them: a valve that
// goes silent mid-move, two valves claiming one address, a valve restarting into its boot code,
// and the simulator's churn. The simulated valves are made to fail with the simulator's hooks;
// an independent DDS participant commands and watches. Runs inside a private network namespace
// (tests/netns/isolated). Recovery times are printed as "[ measured ]" lines (docs/faults.md).

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <map>

#include "gateway_fixture.hpp"
#include "support/dds_peer.hpp"
#include "support/eventually.hpp"
#include "support/test_domain.hpp"
#include "teejet/sim/simulator.hpp"
#include "teejet/valvePubSubTypes.h"

namespace teejet::gateway {
namespace {

using namespace std::chrono_literals;
using teejet::testing::eventually;
using teejet::testing::latest_by_serial;
using teejet::testing::test_domain;
using Ecu = teejet::testing::DdsPeer;
using Clock = std::chrono::steady_clock;

using fixture::make_gateway;
using fixture::sim_config;
using teejet::testing::move_to;
using teejet::testing::request;

std::uint32_t cycles_of(Gateway& gateway, std::uint32_t serial) {
  return gateway.simulator()->inspect(
      [&](const sim::ValveBank& bank) { return bank.valve_with_serial(serial)->cycle_count(); });
}

long long ms(Clock::duration d) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(d).count();
}

const std::vector<CommandState> kDone{COMMAND_ACCEPTED, COMMAND_COMPLETED};

class ValveFaultsE2E : public ::testing::Test {
 protected:
  void start(std::size_t valves, GatewayConfig config) {
    gateway = make_gateway(config);
    ASSERT_TRUE(gateway->start());
    presence = ecu.reader<ValvePresence>();
    ASSERT_TRUE(eventually(
        [&] {
          latest_by_serial(presence, seen);
          return seen.size() == valves &&
                 std::all_of(seen.begin(), seen.end(), [](auto& v) { return v.second.online(); });
        },
        15s))
        << "the ECU never saw the simulated valves online";
  }

  // Waits until the ECU's latest presence of `serial` satisfies `condition`.
  bool presence_becomes(std::uint32_t serial,
                        const std::function<bool(const ValvePresence&)>& condition) {
    return eventually(
        [&] {
          latest_by_serial(presence, seen);
          return seen.contains(serial) && condition(seen[serial]);
        },
        15s);
  }

  Ecu ecu{test_domain(), "faults-ecu"};
  std::unique_ptr<Gateway> gateway;
  eprosima::fastdds::dds::DataReader* presence = nullptr;
  std::map<std::uint32_t, ValvePresence> seen;
};

TEST_F(ValveFaultsE2E, AValveSilentMidMoveEndsItsCommandAndComesBackAsTheSameInstance) {
  start(3, sim_config("gw-silent", 3));
  const auto id = ecu.send(move_to(3, 90.0f, 10));  // 18 deg/s: 5 s of travel
  ASSERT_TRUE(eventually([&] { return cycles_of(*gateway, 3) == 1; }, 15s));
  const auto off_at = Clock::now();
  ASSERT_TRUE(gateway->simulator()->power_off(3));
  const auto statuses = ecu.follow(id);
  const auto ended_after = Clock::now() - off_at;
  ASSERT_EQ(Ecu::states(statuses), (std::vector{COMMAND_ACCEPTED, COMMAND_TIMED_OUT}));
  EXPECT_EQ(statuses.back().reason().to_string(), "valve TJV000003 went offline");
  ASSERT_TRUE(presence_becomes(3, [](const ValvePresence& p) { return !p.online(); }));
  std::printf("[ measured ] e2e silent valve: TIMED_OUT at the ECU %lld ms after power-off\n",
              ms(ended_after));
  auto rejected = ecu.follow(ecu.send(move_to(3, 0.0f)));
  ASSERT_EQ(Ecu::states(rejected), std::vector{COMMAND_REJECTED});
  EXPECT_EQ(rejected[0].reason().to_string(), "valve TJV000003 is offline");

  const auto on_at = Clock::now();
  ASSERT_TRUE(gateway->simulator()->power_on(3));
  ASSERT_TRUE(presence_becomes(3, [](const ValvePresence& p) { return p.online(); }));
  std::printf("[ measured ] e2e silent valve: online at the ECU %lld ms after power-on\n",
              ms(Clock::now() - on_at));
  EXPECT_EQ(seen[3].address(), 0xDA);
  EXPECT_EQ(seen.size(), 3u);  // the same instance (key: serial), no new one
  EXPECT_EQ(Ecu::states(ecu.follow(ecu.send(move_to(3, 0.0f)))), kDone);
}

TEST_F(ValveFaultsE2E, TwoValvesAtOneAddressAreRejectedNamingBothUntilOneMovesAway) {
  start(4, sim_config("gw-conflict", 4));
  const auto forced_at = Clock::now();
  ASSERT_TRUE(gateway->simulator()->force_address(3, 0xD9));
  ASSERT_TRUE(eventually([&] { return gateway->bridge().counters().address_conflicts == 1; }, 15s));
  std::printf("[ measured ] e2e address conflict detected %lld ms after the second claim\n",
              ms(Clock::now() - forced_at));
  for (const std::uint32_t serial : {2u, 3u}) {
    auto rejected = ecu.follow(ecu.send(move_to(serial, 45.0f)));
    ASSERT_EQ(Ecu::states(rejected), std::vector{COMMAND_REJECTED}) << serial;
    EXPECT_EQ(rejected[0].reason().to_string(),
              "address 0xD9 is claimed by TJV000002 and TJV000003");
    EXPECT_EQ(cycles_of(*gateway, serial), 0u);
  }
  // Valves elsewhere are unaffected.
  EXPECT_EQ(Ecu::states(ecu.follow(ecu.send(move_to(1, 10.0f)))), kDone);

  const auto moved_at = Clock::now();
  ASSERT_TRUE(gateway->simulator()->add_valve(sim::ValveConfig{.serial = 10}));  // re-ranks
  ASSERT_TRUE(eventually(
      [&] { return Ecu::states(ecu.follow(ecu.send(move_to(2, 20.0f)))) == kDone; }, 15s));
  std::printf("[ measured ] e2e address conflict cleared, commands work %lld ms after the move\n",
              ms(Clock::now() - moved_at));
  EXPECT_EQ(Ecu::states(ecu.follow(ecu.send(move_to(3, 20.0f)))), kDone);
  EXPECT_EQ(gateway->bridge().counters().address_conflicts, 1u);
}

TEST_F(ValveFaultsE2E, AValveRestartingIntoBootCodeEndsItsCommandAndTakesOnlyRequests) {
  start(2, sim_config("gw-boot", 2));
  const auto id = ecu.send(move_to(2, 90.0f, 10));
  ASSERT_TRUE(eventually([&] { return cycles_of(*gateway, 2) == 1; }, 15s));
  const auto restart_at = Clock::now();
  ASSERT_TRUE(gateway->simulator()->power_off(2));
  ASSERT_TRUE(gateway->simulator()->power_on(2, /*boot_mode=*/true));
  const auto statuses = ecu.follow(id);
  const auto ended_after = Clock::now() - restart_at;
  ASSERT_EQ(Ecu::states(statuses), (std::vector{COMMAND_ACCEPTED, COMMAND_TIMED_OUT}));
  EXPECT_EQ(statuses.back().reason().to_string(),
            "valve TJV000002 restarted: it is running boot code");
  std::printf("[ measured ] e2e restart into boot code: TIMED_OUT at the ECU %lld ms after\n",
              ms(ended_after));
  ASSERT_TRUE(presence_becomes(2, [](const ValvePresence& p) { return p.boot_mode(); }));
  EXPECT_TRUE(seen[2].online());

  auto rejected = ecu.follow(ecu.send(move_to(2, 0.0f)));
  ASSERT_EQ(Ecu::states(rejected), std::vector{COMMAND_REJECTED});
  EXPECT_EQ(rejected[0].reason().to_string(), "valve TJV000002 is running boot code");
  EXPECT_EQ(cycles_of(*gateway, 2), 1u);  // never reached the valve
  EXPECT_EQ(Ecu::states(ecu.follow(ecu.send(request(2, TELEMETRY_VERSION)))), kDone);

  const auto app_at = Clock::now();
  ASSERT_TRUE(gateway->simulator()->power_off(2));
  ASSERT_TRUE(gateway->simulator()->power_on(2));
  ASSERT_TRUE(presence_becomes(2, [](const ValvePresence& p) { return !p.boot_mode(); }));
  EXPECT_EQ(Ecu::states(ecu.follow(ecu.send(move_to(2, 0.0f)))), kDone);
  std::printf("[ measured ] e2e back in application code: a move completed %lld ms after\n",
              ms(Clock::now() - app_at));
}

TEST_F(ValveFaultsE2E, TheChurnTakesValvesOfflineAndBackWhileTheRestKeepsWorking) {
  auto config = sim_config("gw-churn", 4);
  config.sim_churn_period = 3s;  // off for offline_after + 1 s = 2.5 s
  config.sim_churn_seed = 11;
  start(4, config);
  std::map<std::uint32_t, int> went_offline;
  std::map<std::uint32_t, bool> was_online;
  for (const auto& [serial, p] : seen) was_online[serial] = p.online();
  // Two churn cycles: each churned valve is seen offline, and everything is online at the end.
  ASSERT_TRUE(eventually(
      [&] {
        latest_by_serial(presence, seen);
        for (const auto& [serial, p] : seen) {
          if (was_online[serial] && !p.online()) ++went_offline[serial];
          was_online[serial] = p.online();
        }
        return gateway->simulator()->churn_count() >= 2 &&
               gateway->simulator()->assignments().size() == 4 &&
               std::all_of(seen.begin(), seen.end(), [](auto& v) { return v.second.online(); });
      },
      20s));
  int offline_events = 0;
  for (const auto& [serial, count] : went_offline) offline_events += count;
  EXPECT_GE(offline_events, 2);
  for (std::uint32_t serial = 1; serial <= 4; ++serial) {
    std::vector<CommandState> states;
    ASSERT_TRUE(eventually(
        [&] {
          states =
              Ecu::states(ecu.follow(ecu.send(move_to(serial, 5.0f * static_cast<float>(serial)))));
          return states == kDone;
        },
        15s))
        << "TJV00000" << serial;
  }
}

}  // namespace
}  // namespace teejet::gateway
