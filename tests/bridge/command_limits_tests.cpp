// Issue 10, item 3: what the bridge does with a commander that floods one valve or names a
// valve that is not on its bus. What an ECU would see on DDS, what a valve would see on CAN.

#include <gtest/gtest.h>

#include "support/recording_sink.hpp"
#include "support/valve_commands.hpp"
#include "teejet/bridge/bridge.hpp"
#include "teejet/can/virtual_bus.hpp"

namespace teejet::bridge {
namespace {

using namespace std::chrono_literals;

using teejet::testing::from;
using teejet::testing::move_to;
using teejet::testing::RecordingSink;
using teejet::testing::stop;

constexpr Timestamp kStart{1'700'000'000s};

class CommandLimits : public ::testing::Test {
 protected:
  CommandLimits() {
    EXPECT_TRUE(gateway_bus.open());
    EXPECT_TRUE(valve_side.open());
  }

  BridgeConfig config() {
    BridgeConfig c;
    c.can_interface = "virtual:" + bus_name;
    c.poll.clear();  // only the commands' frames on the wire
    c.isobus.claim = false;
    return c;
  }

  // Valve `serial` announces itself at 0xD7 + serial.
  void announce(Bridge& bridge, std::uint32_t serial) {
    const auto address = static_cast<std::uint8_t>(0xD7 + serial);
    bridge.on_frame(
        {codec::encode(address, codec::IAmHere{0x000123, serial, false}).value(), clock->wall()});
  }

  // Frames put on the bus for `address` since the last call.
  std::size_t frames_to(std::uint8_t address) {
    std::size_t n = 0;
    while (auto f = valve_side.receive(0ms)) {
      const auto decoded = codec::decode(f->frame);
      if (decoded && decoded->route.valve_address == address) ++n;
    }
    return n;
  }

  // `c` from the flooding commander, numbered in the order the test writes them.
  ValveCommand flood(const ValveCommand& c) { return from("flood", ++next_id, c); }

  std::string bus_name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
  can::VirtualBus gateway_bus{bus_name, {.filters = can::controller_side_filters()}};
  can::VirtualBus valve_side{bus_name,
                             {.filters = can::valve_side_filters(), .queue_limit = 100'000}};
  RecordingSink sink;
  std::shared_ptr<ManualClock> clock = std::make_shared<ManualClock>(kStart);
  std::uint32_t next_id = 0;
};

TEST_F(CommandLimits, AFloodToOneValveSendsTheBurstThenTheRateAndRejectsTheRest) {
  Bridge bridge(config(), gateway_bus, sink, clock);  // 100/s, burst 20
  announce(bridge, 1);
  announce(bridge, 2);
  for (int i = 0; i < 1000; ++i) bridge.on_command(flood(move_to(1, static_cast<float>(i % 90))));
  EXPECT_EQ(frames_to(0xD8), 20u);
  EXPECT_EQ(sink.count(COMMAND_ACCEPTED), 20u);
  EXPECT_EQ(sink.count(COMMAND_SUPERSEDED), 19u);  // each move replaced the one before
  EXPECT_EQ(sink.count(COMMAND_REJECTED), 980u);
  EXPECT_EQ(sink.statuses().back().reason().to_string(),
            "not sent: over the limit of 100 commands/s (burst 20) to valve TJV000001 "
            "(commands.rate_per_valve, commands.burst_per_valve)");
  EXPECT_EQ(bridge.counters().commands_rate_limited, 980u);

  // Another valve has a bucket of its own.
  bridge.on_command(flood(move_to(2, 10)));
  EXPECT_EQ(sink.statuses().back().state(), COMMAND_ACCEPTED);
  EXPECT_EQ(frames_to(0xD9), 1u);

  // 100 ms later the bucket holds 10 commands again; a second later it is full (20), not 100.
  clock->advance(100ms);
  for (int i = 0; i < 50; ++i) bridge.on_command(flood(move_to(1, 5)));
  EXPECT_EQ(frames_to(0xD8), 10u);
  clock->advance(10s);
  for (int i = 0; i < 50; ++i) bridge.on_command(flood(move_to(1, 5)));
  EXPECT_EQ(frames_to(0xD8), 20u);
}

TEST_F(CommandLimits, AFloodOfMovesNeverTakesAwayTheStop) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 1);
  for (int i = 0; i < 100; ++i) bridge.on_command(flood(move_to(1, 40)));
  EXPECT_EQ(frames_to(0xD8), 20u);
  const auto stop_command = flood(stop(1));
  bridge.on_command(stop_command);
  EXPECT_EQ(sink.states_of(stop_command.command_id()),
            (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
  EXPECT_EQ(frames_to(0xD8), 1u);
  // A flood of Stops is bounded by its own bucket all the same.
  for (int i = 0; i < 100; ++i) bridge.on_command(flood(stop(1)));
  EXPECT_EQ(frames_to(0xD8), 19u);
}

TEST_F(CommandLimits, RateZeroSendsEveryCommand) {
  auto c = config();
  c.command_rate_per_valve = 0;
  Bridge bridge(c, gateway_bus, sink, clock);
  announce(bridge, 1);
  for (int i = 0; i < 1000; ++i) bridge.on_command(flood(move_to(1, 30)));
  EXPECT_EQ(frames_to(0xD8), 1000u);
  EXPECT_EQ(sink.count(COMMAND_REJECTED), 0u);
}

TEST_F(CommandLimits, UnknownSerialsAreIgnoredOrRejectedAsConfigured) {
  {
    Bridge bridge(config(), gateway_bus, sink, clock);
    announce(bridge, 1);
    bridge.on_command(flood(move_to(99, 10)));
    EXPECT_TRUE(sink.statuses().empty());
    EXPECT_EQ(bridge.counters().commands_ignored, 1u);
  }
  auto c = config();
  c.reject_unknown_serials = true;
  Bridge bridge(c, gateway_bus, sink, clock);
  announce(bridge, 1);
  bridge.on_command(flood(move_to(99, 10)));
  ASSERT_EQ(sink.statuses().size(), 1u);
  EXPECT_EQ(sink.statuses()[0].state(), COMMAND_REJECTED);
  EXPECT_EQ(sink.statuses()[0].reason().to_string(),
            "no valve TJV000099 on this gateway's bus (virtual:" + bus_name + ")");
  EXPECT_EQ(bridge.counters().commands_ignored, 0u);
  EXPECT_EQ(frames_to(0xD8), 0u);
}

}  // namespace
}  // namespace teejet::bridge
