// Valve faults against the gateway engine, in-process: the simulator's valves on a VirtualBus, a
// Bridge reading it as the gateway runtime does, the real clock. A valve that goes silent
// mid-move, two valves claiming one address, a valve restarting into its boot code: what an ECU
// sees (presence, command statuses, telemetry) and how long recovery takes. Every wait is for a
// condition with a deadline; the times measured are printed as "[ measured ]" lines, not
// bounded (a loaded machine stretches them): bench/run-test-timings.sh collects them.

#include <gtest/gtest.h>

#include <thread>

#include "support/eventually.hpp"
#include "support/recording_sink.hpp"
#include "support/valve_commands.hpp"
#include "teejet/bridge/bridge.hpp"
#include "teejet/can/virtual_bus.hpp"
#include "teejet/sim/simulator.hpp"

namespace teejet::bridge {
namespace {

using namespace std::chrono_literals;
using teejet::testing::eventually;
using teejet::testing::from;
using teejet::testing::move_to;
using teejet::testing::RecordingSink;
using teejet::testing::request;
using Clock = std::chrono::steady_clock;

// What a failing wait costs, never what a passing one takes: a power glitch's positions flow again
// 2.3 s after it on an idle machine, and took over 10 s under ASan beside the ci stage's tests.
constexpr auto kDeadline = 30s;
constexpr auto kOfflineAfter = 1500ms;
constexpr const char* kCommander = "faults-test";

class ValveFaults : public ::testing::Test {
 protected:
  void start(std::uint32_t valves) {
    const std::string name =
        std::string("faults-") + ::testing::UnitTest::GetInstance()->current_test_info()->name();
    sim::SimulatorOptions options;
    for (std::uint32_t serial = 1; serial <= valves; ++serial) {
      options.valves.push_back(sim::ValveConfig{.serial = serial});
    }
    simulator = std::make_unique<sim::Simulator>(
        std::make_unique<can::VirtualBus>(name, can::VirtualBusOptions{can::valve_side_filters()}),
        std::move(options));
    gateway_bus = std::make_unique<can::VirtualBus>(
        name, can::VirtualBusOptions{can::controller_side_filters()});
    ASSERT_TRUE(gateway_bus->open());
    BridgeConfig config;
    config.offline_after = kOfflineAfter;
    config.isobus.claim = false;  // the valves' faults alone
    bridge = std::make_unique<Bridge>(config, *gateway_bus, sink);
    pump = std::jthread([this](const std::stop_token& stop) { run(stop); });
    ASSERT_TRUE(simulator->start());
    for (std::uint32_t serial = 1; serial <= valves; ++serial) {
      ASSERT_TRUE(eventually([&] { return online(serial); }, kDeadline)) << serial;
    }
  }

  void TearDown() override {
    if (simulator) simulator->stop();
    pump = {};
  }

  // The gateway runtime's bus loop, reduced: frames in, ticks when due.
  void run(const std::stop_token& stop) {
    while (!stop.stop_requested()) {
      if (auto frame = gateway_bus->receive(5ms)) bridge->on_frame(*frame);
      if (std::chrono::steady_clock::now() >= bridge->next_deadline()) bridge->tick();
    }
  }

  bool online(std::uint32_t serial) const {
    const auto presence = sink.last_presence(serial);
    return presence && presence->sample.online();
  }

  // Sends and waits for its final status.
  RecordingSink::Arrived<CommandStatus> run_command(const ValveCommand& command) {
    bridge->on_command(command);
    std::optional<RecordingSink::Arrived<CommandStatus>> status;
    EXPECT_TRUE(eventually(
        [&] { return (status = sink.final_status(command.command_id())).has_value(); }, kDeadline))
        << "no final status for command " << command.command_id();
    return status.value_or(RecordingSink::Arrived<CommandStatus>{});
  }

  template <class Fn>
  auto inspect_valve(std::uint32_t serial, Fn&& fn) {
    return simulator->inspect(
        [&](const sim::ValveBank& bank) { return fn(*bank.valve_with_serial(serial)); });
  }

  static long long ms(Clock::duration d) {
    return std::chrono::duration_cast<std::chrono::milliseconds>(d).count();
  }

  RecordingSink sink;
  std::unique_ptr<sim::Simulator> simulator;
  std::unique_ptr<can::VirtualBus> gateway_bus;
  std::unique_ptr<Bridge> bridge;
  std::jthread pump;
};

// (a) The highest serial: nobody takes its address, it simply goes quiet.
TEST_F(ValveFaults, AValveThatGoesSilentMidMoveEndsItsCommandWithinTheOfflineTimeAndComesBack) {
  start(3);
  bridge->on_command(from(kCommander, 1, move_to(3, 90.0F, 10)));  // 9 deg/s: 10 s of travel
  ASSERT_TRUE(eventually(
      [&] {
        return inspect_valve(3, [](const sim::SimulatedValve& v) { return v.cycle_count() == 1; });
      },
      kDeadline));
  const auto off_at = Clock::now();
  ASSERT_TRUE(simulator->power_off(3));
  std::optional<RecordingSink::Arrived<CommandStatus>> ended;
  ASSERT_TRUE(eventually([&] { return (ended = sink.final_status(1)).has_value(); }, kDeadline));
  EXPECT_EQ(ended->sample.state(), COMMAND_TIMED_OUT);
  EXPECT_EQ(ended->sample.reason().to_string(), "valve TJV000003 went offline");
  const auto ended_after = ended->at - off_at;
  EXPECT_FALSE(online(3));
  std::printf("[ measured ] silent valve: command ended %lld ms after power-off\n",
              ms(ended_after));

  const auto on_at = Clock::now();
  ASSERT_TRUE(simulator->power_on(3));
  ASSERT_TRUE(eventually([&] { return online(3); }, kDeadline));
  const auto back_after = sink.last_presence(3)->at - on_at;
  // Polling re-armed: position samples flow again.
  ASSERT_TRUE(eventually([&] { return sink.positions_since(3, on_at) >= 3; }, kDeadline));
  EXPECT_EQ(sink.last_presence(3)->sample.address(), 0xDA);
  std::printf("[ measured ] silent valve: online %lld ms after power-on\n", ms(back_after));
  const auto done = run_command(from(kCommander, 2, move_to(3, 0.0F)));
  EXPECT_EQ(done.sample.state(), COMMAND_COMPLETED) << done.sample.reason().to_string();
}

// (a) A middle serial: the valve above moves down into its address, so it is displaced rather
// than merely quiet; its command must still end within the offline time.
TEST_F(ValveFaults, AValveWhoseAddressIsTakenWhileSilentEndsItsCommandWithinTheOfflineTime) {
  start(3);
  bridge->on_command(from(kCommander, 1, move_to(2, 90.0F, 10)));
  ASSERT_TRUE(eventually(
      [&] {
        return inspect_valve(2, [](const sim::SimulatedValve& v) { return v.cycle_count() == 1; });
      },
      kDeadline));
  const auto off_at = Clock::now();
  ASSERT_TRUE(simulator->power_off(2));
  std::optional<RecordingSink::Arrived<CommandStatus>> ended;
  ASSERT_TRUE(eventually([&] { return (ended = sink.final_status(1)).has_value(); }, kDeadline));
  EXPECT_EQ(ended->sample.state(), COMMAND_TIMED_OUT);
  EXPECT_EQ(ended->sample.reason().to_string(), "valve TJV000002 went offline");
  std::printf("[ measured ] displaced silent valve: command ended %lld ms after power-off\n",
              ms(ended->at - off_at));
  // TJV000003 moved into 0xD9 and works there.
  EXPECT_EQ(run_command(from(kCommander, 2, move_to(3, 10.0F))).sample.state(), COMMAND_COMPLETED);
  EXPECT_EQ(sink.last_presence(3)->sample.address(), 0xD9);
  // Back: re-ranked, 2 at 0xD9, 3 at 0xDA again, both commanded successfully.
  ASSERT_TRUE(simulator->power_on(2));
  ASSERT_TRUE(eventually(
      [&] {
        return online(2) && sink.last_presence(2)->sample.address() == 0xD9 &&
               sink.last_presence(3)->sample.address() == 0xDA;
      },
      kDeadline));
  EXPECT_EQ(run_command(from(kCommander, 3, move_to(2, 0.0F))).sample.state(), COMMAND_COMPLETED);
  EXPECT_EQ(run_command(from(kCommander, 4, move_to(3, 0.0F))).sample.state(), COMMAND_COMPLETED);
  EXPECT_EQ(bridge->counters().address_conflicts, 0u);  // a restart is no conflict
}

// (a) A power glitch: off and on again at once, at an address nobody took. Its I'm Here looks
// like any other; only its telemetry stops (the automatic resends lived in RAM).
TEST_F(ValveFaults, AValveThatRestartsUnnoticedIsPolledAgainOnceItsTelemetryStops) {
  start(3);
  const auto glitch_at = Clock::now();
  ASSERT_TRUE(simulator->power_off(3));
  ASSERT_TRUE(simulator->power_on(3));
  ASSERT_TRUE(eventually([&] { return sink.positions_since(3, glitch_at) >= 3; }, kDeadline));
  const auto back_after = Clock::now() - glitch_at;
  std::printf("[ measured ] power glitch: positions flowing again %lld ms after the restart\n",
              ms(back_after));
  EXPECT_TRUE(online(3));
  EXPECT_EQ(run_command(from(kCommander, 1, move_to(3, 30.0F))).sample.state(), COMMAND_COMPLETED);
}

// (b)
TEST_F(ValveFaults, TwoValvesAtOneAddressAreRejectedNamingBothAndTheirTelemetryIsDropped) {
  start(4);
  const auto forced_at = Clock::now();
  ASSERT_TRUE(simulator->force_address(3, 0xD9));
  ASSERT_TRUE(eventually([&] { return bridge->counters().address_conflicts == 1; }, kDeadline));
  const auto detected_after = Clock::now() - forced_at;
  std::printf("[ measured ] address conflict detected %lld ms after the second valve claimed it\n",
              ms(detected_after));

  const std::string reason = "address 0xD9 is claimed by TJV000002 and TJV000003";
  for (const std::uint32_t serial : {2u, 3u}) {
    const auto rejected = run_command(from(kCommander, serial * 10, move_to(serial, 45.0F)));
    EXPECT_EQ(rejected.sample.state(), COMMAND_REJECTED);
    EXPECT_EQ(rejected.sample.reason().to_string(), reason);
  }
  EXPECT_EQ(inspect_valve(2, [](const sim::SimulatedValve& v) { return v.cycle_count(); }), 0u);
  EXPECT_EQ(inspect_valve(3, [](const sim::SimulatedValve& v) { return v.cycle_count(); }), 0u);
  // Nothing from 0xD9 is published for either serial while valve 1 keeps reporting.
  const auto watched_from = Clock::now();
  ASSERT_TRUE(eventually([&] { return sink.positions_since(1, watched_from) >= 15; }, kDeadline));
  EXPECT_EQ(sink.positions_since(2, watched_from), 0u);
  EXPECT_EQ(sink.positions_since(3, watched_from), 0u);
  EXPECT_EQ(bridge->counters().address_conflicts, 1u);  // counted once, not per I'm Here

  // A re-rank (a valve added) sends 3 back to 0xDA: the conflict is over.
  const auto moved_at = Clock::now();
  ASSERT_TRUE(simulator->add_valve(sim::ValveConfig{.serial = 10}));
  std::uint32_t id = 100;
  ASSERT_TRUE(eventually(
      [&] {
        return run_command(from(kCommander, ++id, move_to(2, 10.0F))).sample.state() ==
               COMMAND_COMPLETED;
      },
      kDeadline));
  std::printf("[ measured ] address conflict cleared, valve commandable %lld ms after the move\n",
              ms(Clock::now() - moved_at));
  EXPECT_EQ(run_command(from(kCommander, 1000, move_to(3, 10.0F))).sample.state(),
            COMMAND_COMPLETED);
  ASSERT_TRUE(eventually(
      [&] {
        return sink.positions_since(2, moved_at) > 0 && sink.positions_since(3, moved_at) > 0;
      },
      kDeadline));
  EXPECT_EQ(bridge->counters().address_conflicts, 1u);
}

// (b) The other way out: one of the two goes silent.
TEST_F(ValveFaults, AnAddressConflictEndsWhenOneValveGoesSilent) {
  start(4);
  ASSERT_TRUE(simulator->force_address(4, 0xD9));
  ASSERT_TRUE(eventually([&] { return bridge->counters().address_conflicts == 1; }, kDeadline));
  const auto off_at = Clock::now();
  ASSERT_TRUE(simulator->power_off(4));  // the highest: nobody else moves
  std::uint32_t id = 100;
  ASSERT_TRUE(eventually(
      [&] {
        return run_command(from(kCommander, ++id, move_to(2, 10.0F))).sample.state() ==
               COMMAND_COMPLETED;
      },
      kDeadline));
  const auto cleared_after = Clock::now() - off_at;
  std::printf("[ measured ] address conflict cleared %lld ms after one valve went silent\n",
              ms(cleared_after));
  EXPECT_FALSE(online(4));
}

// (c)
TEST_F(ValveFaults, AValveRestartingIntoBootCodeEndsItsCommandAndTakesOnlyRequests) {
  start(2);
  bridge->on_command(from(kCommander, 1, move_to(2, 90.0F, 10)));
  ASSERT_TRUE(eventually(
      [&] {
        return inspect_valve(2, [](const sim::SimulatedValve& v) { return v.cycle_count() == 1; });
      },
      kDeadline));
  const auto restart_at = Clock::now();
  ASSERT_TRUE(simulator->power_off(2));
  ASSERT_TRUE(simulator->power_on(2, /*boot_mode=*/true));
  std::optional<RecordingSink::Arrived<CommandStatus>> ended;
  ASSERT_TRUE(eventually([&] { return (ended = sink.final_status(1)).has_value(); }, kDeadline));
  EXPECT_EQ(ended->sample.state(), COMMAND_TIMED_OUT);
  EXPECT_EQ(ended->sample.reason().to_string(),
            "valve TJV000002 restarted: it is running boot code");
  std::printf("[ measured ] restart into boot code: command ended %lld ms after the restart\n",
              ms(ended->at - restart_at));
  const auto presence = sink.last_presence(2);
  EXPECT_TRUE(presence->sample.online());
  EXPECT_TRUE(presence->sample.boot_mode());

  const auto rejected = run_command(from(kCommander, 2, move_to(2, 0.0F)));
  EXPECT_EQ(rejected.sample.state(), COMMAND_REJECTED);
  EXPECT_EQ(rejected.sample.reason().to_string(), "valve TJV000002 is running boot code");
  EXPECT_EQ(inspect_valve(2, [](const sim::SimulatedValve& v) { return v.cycle_count(); }), 1u);
  const auto asked = run_command(from(kCommander, 3, request(2, TELEMETRY_VERSION)));
  EXPECT_EQ(asked.sample.state(), COMMAND_COMPLETED) << asked.sample.reason().to_string();

  const auto app_at = Clock::now();
  ASSERT_TRUE(simulator->power_off(2));
  ASSERT_TRUE(simulator->power_on(2));
  ASSERT_TRUE(eventually([&] { return !sink.last_presence(2)->sample.boot_mode(); }, kDeadline));
  ASSERT_TRUE(eventually([&] { return sink.positions_since(2, app_at) >= 3; }, kDeadline));
  std::printf("[ measured ] back in application code: polled again %lld ms after the restart\n",
              ms(Clock::now() - app_at));
  EXPECT_EQ(run_command(from(kCommander, 4, move_to(2, 0.0F))).sample.state(), COMMAND_COMPLETED);
}

}  // namespace
}  // namespace teejet::bridge
