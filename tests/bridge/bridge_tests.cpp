// The gateway engine against a virtual bus: what an ECU would see on DDS and what a valve would
// see on CAN.

#include <gtest/gtest.h>

#include <algorithm>

#include "support/recording_sink.hpp"
#include "support/valve_commands.hpp"
#include "teejet/bridge/bridge.hpp"
#include "teejet/can/virtual_bus.hpp"
#include "teejet/dds/names.hpp"

namespace teejet::bridge {
namespace {

using namespace std::chrono_literals;

using teejet::testing::command;
using teejet::testing::from;
using teejet::testing::move_to;
using teejet::testing::RecordingSink;
using teejet::testing::request;
using teejet::testing::stop;

constexpr Timestamp kStart{1'700'000'000s};
constexpr const char* kEcu = "test-ecu";

class BridgeTest : public ::testing::Test {
 protected:
  BridgeTest() {
    EXPECT_TRUE(gateway_bus.open());
    EXPECT_TRUE(valve_side.open());
  }

  BridgeConfig config() {
    BridgeConfig c;
    c.gateway_name = "gw-test";
    c.can_interface = "virtual:" + bus_name;
    c.isobus.claim = false;  // the valves' side here; claiming has tests of its own
    return c;
  }

  // Frames the bridge put on the bus, as the valves see them.
  std::vector<codec::CanFrame> sent() {
    std::vector<codec::CanFrame> frames;
    while (auto f = valve_side.receive(0ms)) frames.push_back(f->frame);
    return frames;
  }

  static can::TimedFrame from_valve(std::uint8_t address, const codec::FromValveMessage& message,
                                    Timestamp at) {
    return {codec::encode(address, message).value(), at};
  }

  void announce(Bridge& bridge, std::uint8_t address, std::uint32_t serial, Timestamp when) {
    deliver(bridge, from_valve(address, codec::IAmHere{0x000123, serial, false}, when));
  }

  // Time passes to `when` (the wall and steady clocks together) before each call to the bridge.
  void at(Timestamp when) {
    ASSERT_GE(when, clock->wall()) << "a test must not go back in time";
    clock->advance(when - clock->wall());
  }
  void deliver(Bridge& bridge, const can::TimedFrame& frame) {
    at(frame.received);
    bridge.on_frame(frame);
  }
  void tick_at(Bridge& bridge, Timestamp when) {
    at(when);
    bridge.tick();
  }
  void command_at(Bridge& bridge, Timestamp when, const ValveCommand& c,
                  const std::string& commander = {}) {
    at(when);
    bridge.on_command(c, commander);
  }
  std::size_t stop_all_at(Bridge& bridge, Timestamp when) {
    at(when);
    return bridge.stop_all();
  }
  std::size_t stop_commanded_by_at(Bridge& bridge, Timestamp when, const std::string& commander) {
    at(when);
    return bridge.stop_commanded_by(commander);
  }

  std::string bus_name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
  can::VirtualBus gateway_bus{bus_name, {.filters = can::controller_side_filters()}};
  can::VirtualBus valve_side{bus_name, {.filters = can::valve_side_filters()}};
  RecordingSink sink;
  std::shared_ptr<ManualClock> clock = std::make_shared<ManualClock>(kStart);
};

TEST_F(BridgeTest, IAmHerePublishesPresenceAndArmsThePollSchedule) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 123456, kStart);

  ASSERT_EQ(sink.presences().size(), 1u);
  const auto presence = sink.presences().at(0);
  EXPECT_EQ(presence.serial(), 123456u);
  EXPECT_EQ(presence.address(), 0xD8);
  EXPECT_TRUE(presence.online());
  EXPECT_EQ(presence.part_number(), 0x000123u);
  EXPECT_EQ(presence.last_seen_ns(), unix_nanoseconds(kStart));
  EXPECT_EQ(presence.gateway().to_string(), "gw-test");

  const auto frames = sent();
  ASSERT_EQ(frames.size(), 9u);
  const std::vector<std::pair<std::uint8_t, std::uint8_t>> expected{
      {0x10, 0xFF}, {0x11, 1},  {0x12, 10}, {0x13, 10}, {0x14, 10},
      {0x15, 10},   {0x16, 10}, {0x17, 50}, {0x18, 50}};
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(frames[i].id, 0x18EFD8D5u);
    EXPECT_EQ(frames[i].data[0], expected[i].first);
    EXPECT_EQ(frames[i].data[1], expected[i].second);
  }
}

TEST_F(BridgeTest, HeartbeatsRefreshPresenceWithoutPollingAgain) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 1, kStart);
  (void)sent();
  announce(bridge, 0xD8, 1, kStart + 1s);
  EXPECT_TRUE(sent().empty());
  ASSERT_EQ(sink.presences().size(), 2u);
  EXPECT_EQ(sink.presences()[1].last_seen_ns(), unix_nanoseconds(kStart + 1s));
}

// A power glitch in the middle of the poll burst: the requests that reached the valve before it
// went off are lost with its RAM, the ones after are resent. Each stopped reply is asked for
// again, alone, at the I'm Here after its quiet limit; asked for in vain, ever more rarely.
TEST_F(BridgeTest, AReplyThatStoppedIsPolledAgainWhileOthersStillFlow) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 1, kStart);
  ASSERT_EQ(sent().size(), 9u);
  // Every second: I'm Here and the replies resent once a second, but no Position (resent every
  // 0.1 s, quiet limit 2 s); run time and cycle counts (every 5 s) are quiet only after 10 s.
  auto second = [&](std::chrono::milliseconds at) {
    for (const codec::FromValveMessage& reply :
         {codec::FromValveMessage{codec::Temperature{}}, codec::FromValveMessage{codec::Voltage{}},
          codec::FromValveMessage{codec::RunCurrent{}},
          codec::FromValveMessage{codec::DegreesPerSecond{}},
          codec::FromValveMessage{codec::SpeedDirection{}}}) {
      deliver(bridge, from_valve(0xD8, reply, kStart + at - 10ms));
    }
    announce(bridge, 0xD8, 1, kStart + at);
    return sent();
  };
  EXPECT_TRUE(second(1000ms).empty());
  EXPECT_TRUE(second(2000ms).empty());  // not over the limit yet
  auto again = second(3000ms);
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(again[0].id, 0x18EFD8D5u);
  EXPECT_EQ(again[0].data[0], 0x11);  // Request Position, resent every 0.1 s as first asked
  EXPECT_EQ(again[0].data[1], 1);
  // Asked in vain: the limit doubles to 4 s, then 8 s.
  for (auto at = 4000ms; at <= 7000ms; at += 1000ms) EXPECT_TRUE(second(at).empty()) << at.count();
  EXPECT_EQ(second(8000ms).size(), 1u);
  // Heard again: back to 2 s, and it keeps flowing.
  deliver(bridge, from_valve(0xD8, codec::Position{12.5}, kStart + 8100ms));
  EXPECT_EQ(std::get<ValvePosition>(sink.samples().back()).degrees(), 12.5f);
  for (auto at = 8200ms; at <= 9900ms; at += 100ms) {
    deliver(bridge, from_valve(0xD8, codec::Position{12.5}, kStart + at));
  }
  EXPECT_TRUE(second(10000ms).empty());
  // Run time and cycle counts never came: quiet at 10 s after the poll, both asked at once.
  again = second(11000ms);
  ASSERT_EQ(again.size(), 2u);
  EXPECT_EQ(again[0].data[0], 0x17);
  EXPECT_EQ(again[1].data[0], 0x18);
}

TEST_F(BridgeTest, TelemetryIsPublishedForTheSerialStampedWithReceiveTime) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD9, 4711, kStart);
  deliver(bridge, from_valve(0xD9, codec::Position{123.4}, kStart + 5ms));
  ASSERT_EQ(sink.samples().size(), 1u);
  const auto position = std::get<ValvePosition>(sink.samples().at(0));
  EXPECT_EQ(position.serial(), 4711u);
  EXPECT_FLOAT_EQ(position.degrees(), 123.4f);
  EXPECT_EQ(position.received_ns(), unix_nanoseconds(kStart + 5ms));
}

TEST_F(BridgeTest, TelemetryFromAnUnannouncedAddressIsCountedNotGuessed) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  deliver(bridge, from_valve(0xE0, codec::Position{10.0}, kStart));
  EXPECT_TRUE(sink.samples().empty());
  EXPECT_EQ(bridge.counters().unattributed, 1u);
}

TEST_F(BridgeTest, MalformedFramesAreCountedAndReportedInGatewayStatus) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  codec::CanFrame short_position{.id = 0x18EFD5D8, .dlc = 2, .data = {0x02, 0x01}};
  deliver(bridge, {short_position, kStart});
  EXPECT_EQ(bridge.counters().decode_errors, 1u);
  EXPECT_EQ(bridge.counters().last_decode_error, "position needs 3 bytes, got 2");
  tick_at(bridge, kStart);
  tick_at(bridge, kStart + 1s);
  ASSERT_EQ(sink.gateway_statuses().size(), 1u);
  EXPECT_EQ(sink.gateway_statuses()[0].decode_errors(), 1u);
  EXPECT_EQ(sink.gateway_statuses()[0].gateway().to_string(), "gw-test");
}

TEST_F(BridgeTest, AReaddressedValveKeepsItsIdentityAndCommandsFollowIt) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 500, kStart);
  (void)sent();
  announce(bridge, 0xDA, 500, kStart + 1s);  // a valve with a lower serial joined
  EXPECT_EQ(sink.presences().back().address(), 0xDA);
  const auto repoll = sent();
  ASSERT_EQ(repoll.size(), 9u);
  EXPECT_EQ(repoll[0].id, 0x18EFDAD5u);

  deliver(bridge, from_valve(0xDA, codec::Position{45.0}, kStart + 1100ms));
  EXPECT_EQ(std::get<ValvePosition>(sink.samples().back()).serial(), 500u);

  command_at(bridge, kStart + 2s, from(kEcu, 1, stop(500)));
  const auto frames = sent();
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].id, 0x18EFDAD5u);
  EXPECT_EQ(frames[0].data[0], 0x00);
}

TEST_F(BridgeTest, OfflineAfterThreeSecondsWithoutIAmHere) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 9, kStart);
  tick_at(bridge, kStart + 3s);
  EXPECT_TRUE(sink.presences().back().online());
  tick_at(bridge, kStart + 3s + 1ms);
  EXPECT_FALSE(sink.presences().back().online());
  EXPECT_EQ(sink.presences().back().serial(), 9u);

  (void)sent();
  command_at(bridge, kStart + 4s, from(kEcu, 7, stop(9)));
  EXPECT_EQ(sink.states_of(7), std::vector{COMMAND_REJECTED});
  EXPECT_EQ(sink.last_reason(), "valve TJV000009 is offline");
  EXPECT_TRUE(sent().empty());

  announce(bridge, 0xD8, 9, kStart + 5s);
  EXPECT_TRUE(sink.presences().back().online());
  EXPECT_EQ(sent().size(), 9u);  // polling re-armed
}

TEST_F(BridgeTest, CommandsForSerialsThisGatewayDoesNotHaveAreIgnoredSilently) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  command_at(bridge, kStart, from(kEcu, 1, stop(999)));
  EXPECT_TRUE(sink.statuses().empty());
  EXPECT_TRUE(sent().empty());
  EXPECT_EQ(bridge.counters().commands_ignored, 1u);
  EXPECT_FALSE(bridge.owns(999));
}

TEST_F(BridgeTest, OutOfRangeCommandIsRejectedWithReasonAndNeverReachesTheBus) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 1, kStart);
  (void)sent();
  command_at(bridge, kStart, from(kEcu, 3, move_to(1, 360.0f)));
  EXPECT_EQ(sink.states_of(3), std::vector{COMMAND_REJECTED});
  EXPECT_EQ(sink.last_reason(), "target_degrees: degrees 360 is outside 0 to 359.9");
  auto fast = from(kEcu, 4, command(1, COMMAND_MANUAL));
  fast.speed_percent(101);
  command_at(bridge, kStart, fast);
  EXPECT_EQ(sink.last_reason(), "manual: speed_percent 101 is outside 0 to 100");
  auto shortest = from(kEcu, 5, command(1, COMMAND_DEGREES_FROM_POSITION));
  shortest.direction(DIRECTION_SHORTEST);
  command_at(bridge, kStart, shortest);
  EXPECT_EQ(sink.last_reason(),
            "degrees_from_position: direction \"shortest\" is not one of close, open");
  EXPECT_TRUE(sent().empty());
  EXPECT_EQ(bridge.counters().commands_rejected, 3u);
}

TEST_F(BridgeTest, TargetMoveIsSentThenCompletedFromPositionTelemetry) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 1, kStart);
  deliver(bridge, from_valve(0xD8, codec::Position{0.0}, kStart));
  (void)sent();

  command_at(bridge, kStart + 10ms, from(kEcu, 10, move_to(1, 90.0f)));
  const auto frames = sent();
  ASSERT_EQ(frames.size(), 1u);
  const std::array<std::uint8_t, 8> expected{0x02, 100, 0x01, 0x03, 0x84, 0xFF, 0xFF, 0xFF};
  EXPECT_EQ(frames[0].data, expected);
  EXPECT_EQ(sink.states_of(10), std::vector{COMMAND_ACCEPTED});

  deliver(bridge, from_valve(0xD8, codec::Position{45.0}, kStart + 500ms));
  EXPECT_EQ(sink.states_of(10), std::vector{COMMAND_ACCEPTED});
  deliver(bridge, from_valve(0xD8, codec::Position{89.5}, kStart + 1000ms));  // within 1.0
  EXPECT_EQ(sink.states_of(10), (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
  EXPECT_EQ(sink.statuses().back().stamp_ns(), unix_nanoseconds(kStart + 1s));
  // The position that completed the move goes out first: a client reading the position on
  // COMPLETED (valvectl move --wait) shows 89.5, not 45.
  const auto completing = sink.last_sample(1);
  const auto completed = sink.final_status(10);
  ASSERT_TRUE(completing && completed);
  ASSERT_TRUE(std::holds_alternative<ValvePosition>(completing->sample));
  EXPECT_FLOAT_EQ(std::get<ValvePosition>(completing->sample).degrees(), 89.5f);
  EXPECT_LT(completing->sequence, completed->sequence);
}

TEST_F(BridgeTest, TargetMoveThatNeverArrivesTimesOutWithTheReason) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 1, kStart);
  deliver(bridge, from_valve(0xD8, codec::Position{0.0}, kStart));
  deliver(bridge, from_valve(0xD8, codec::DegreesPerSecond{90, codec::Direction::kOpen}, kStart));
  command_at(bridge, kStart,
             from(kEcu, 11, move_to(1, 90.0f)));  // ETA 1 s at 90 dps, plus a 3 s margin
  deliver(bridge, from_valve(0xD8, codec::Position{30.0}, kStart + 1s));
  announce(bridge, 0xD8, 1, kStart + 2s);
  announce(bridge, 0xD8, 1, kStart + 3s);
  tick_at(bridge, kStart + 3999ms);
  EXPECT_EQ(sink.states_of(11), std::vector{COMMAND_ACCEPTED});
  tick_at(bridge, kStart + 4s);
  EXPECT_EQ(sink.states_of(11), (std::vector{COMMAND_ACCEPTED, COMMAND_TIMED_OUT}));
  EXPECT_EQ(sink.states_of(11).size(), 2u);
  const auto last = sink.statuses().back();
  EXPECT_EQ(last.reason().to_string(), "position 30.0 did not reach 90.0 in time");
}

TEST_F(BridgeTest, ANewCommandSupersedesTheRunningOne) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 1, kStart);
  deliver(bridge, from_valve(0xD8, codec::Position{0.0}, kStart));
  command_at(bridge, kStart, from(kEcu, 20, move_to(1, 90.0f)));
  command_at(bridge, kStart + 100ms, from(kEcu, 21, move_to(1, 10.0f)));
  EXPECT_EQ(sink.states_of(20), (std::vector{COMMAND_ACCEPTED, COMMAND_SUPERSEDED}));
  EXPECT_EQ(sink.states_of(21), std::vector{COMMAND_ACCEPTED});
  const auto statuses = sink.statuses();
  const auto superseded = std::find_if(statuses.begin(), statuses.end(),
                                       [](auto& s) { return s.state() == COMMAND_SUPERSEDED; });
  EXPECT_EQ(superseded->reason().to_string(), "replaced by command 21 from test-ecu");
}

TEST_F(BridgeTest, DegreesFromPositionCompletesAtTheRelativeTarget) {
  auto c = config();
  c.layout = *layout::Layout::make({}, layout::Mechanics{0.0, 90.0});
  Bridge bridge(c, gateway_bus, sink, clock);
  announce(bridge, 0xD8, 1, kStart);
  deliver(bridge, from_valve(0xD8, codec::Position{80.0}, kStart));
  auto relative = from(kEcu, 30, command(1, COMMAND_DEGREES_FROM_POSITION));
  relative.degrees(45.0f);  // 125 clamps to the opened limit, 90
  command_at(bridge, kStart, relative);
  deliver(bridge, from_valve(0xD8, codec::Position{90.0}, kStart + 200ms));
  EXPECT_EQ(sink.states_of(30), (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
}

TEST_F(BridgeTest, FullTurnValveWrapsRelativeTargets) {
  auto c = config();
  c.layout = *layout::Layout::make(
      {{.name = "master", .order = 1, .serial = 1, .mechanics = layout::Mechanics{0.0, 360.0}}});
  Bridge bridge(c, gateway_bus, sink, clock);
  announce(bridge, 0xD8, 1, kStart);
  deliver(bridge, from_valve(0xD8, codec::Position{350.0}, kStart));
  auto relative = from(kEcu, 31, command(1, COMMAND_DEGREES_FROM_POSITION));
  relative.degrees(20.0f);  // 370 wraps to 10
  command_at(bridge, kStart, relative);
  deliver(bridge, from_valve(0xD8, codec::Position{9.6}, kStart + 300ms));
  EXPECT_EQ(sink.states_of(31), (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
}

TEST_F(BridgeTest, MillisecondsToRunCompletesWhenItsTimeIsUp) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 1, kStart);
  auto jog = from(kEcu, 40, command(1, COMMAND_MILLISECONDS_TO_RUN));
  jog.milliseconds(1500);
  command_at(bridge, kStart, jog);
  tick_at(bridge, kStart + 1499ms);
  EXPECT_EQ(sink.states_of(40), std::vector{COMMAND_ACCEPTED});
  tick_at(bridge, kStart + 1500ms);
  EXPECT_EQ(sink.states_of(40), (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
}

TEST_F(BridgeTest, StopAndClearErrorsCompleteOnceSent) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 1, kStart);
  command_at(bridge, kStart, from(kEcu, 50, stop(1)));
  EXPECT_EQ(sink.states_of(50), (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
}

TEST_F(BridgeTest, ErrorsAreLatchedUntilClearErrors) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 1, kStart);
  deliver(bridge, from_valve(0xD8, codec::HighVoltageError{17.2, 16.5}, kStart));
  deliver(bridge, from_valve(0xD8, codec::HighTemperatureError{90, 85}, kStart));
  const auto error = std::get<ValveError>(sink.samples().at(0));
  EXPECT_EQ(error.kind(), ERROR_HIGH_VOLTAGE);
  EXPECT_FLOAT_EQ(error.value(), 17.2f);
  EXPECT_TRUE(sink.cleared().empty());

  (void)sent();
  command_at(bridge, kStart + 1s, from(kEcu, 60, command(1, COMMAND_CLEAR_ERRORS)));
  EXPECT_EQ(sent().at(0).data[0], 0x04);
  const std::vector<std::pair<std::uint32_t, ErrorKind>> cleared{{1, ERROR_HIGH_VOLTAGE},
                                                                 {1, ERROR_HIGH_TEMPERATURE}};
  EXPECT_EQ(sink.cleared(), cleared);
}

TEST_F(BridgeTest, RequestCompletesWhenTheReplyArrivesOrTimesOut) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 1, kStart);
  (void)sent();
  command_at(bridge, kStart, from(kEcu, 70, request(1, TELEMETRY_VERSION)));
  EXPECT_EQ(sent().at(0).data[0], 0x10);
  deliver(bridge, from_valve(0xD8, codec::VersionInfo{{1, 2, 'e'}, {1, 0, 0}}, kStart + 20ms));
  EXPECT_EQ(sink.states_of(70), (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));

  command_at(bridge, kStart + 1s, from(kEcu, 71, request(1, TELEMETRY_VOLTAGE)));
  tick_at(bridge, kStart + 3s);
  EXPECT_EQ(sink.states_of(71), (std::vector{COMMAND_ACCEPTED, COMMAND_TIMED_OUT}));
  EXPECT_EQ(sink.last_reason(), "no reply within 2000 ms");
}

TEST_F(BridgeTest, AOneShotRequestDoesNotEndTheGatewaysPolling) {
  // The sheet: a request sets the resend period "until changed"; a one-shot request would
  // silently stop the gateway's 100 ms position stream, so the gateway puts its schedule back.
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 1, kStart);
  (void)sent();
  command_at(bridge, kStart, from(kEcu, 75, request(1, TELEMETRY_POSITION)));
  EXPECT_EQ(sent().at(0).data[1], 0);  // the client's request, as asked
  deliver(bridge, from_valve(0xD8, codec::Position{12.0}, kStart + 10ms));
  EXPECT_EQ(sink.states_of(75), (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
  const auto restored = sent();
  ASSERT_EQ(restored.size(), 1u);
  EXPECT_EQ(restored[0].data[0], 0x11);
  EXPECT_EQ(restored[0].data[1], 1);  // the schedule's 100 ms again

  // An explicit new period is the client's choice and stands.
  command_at(bridge, kStart + 1s, from(kEcu, 76, request(1, TELEMETRY_POSITION, 50)));
  deliver(bridge, from_valve(0xD8, codec::Position{12.0}, kStart + 1010ms));
  const auto frames = sent();
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].data[1], 50);
}

TEST_F(BridgeTest, BaudRateChangeIsRefusedUnlessAllowed) {
  {
    Bridge bridge(config(), gateway_bus, sink, clock);
    announce(bridge, 0xD8, 1, kStart);
    (void)sent();
    auto baud = from(kEcu, 80, command(1, COMMAND_SET_BAUD_RATE));
    baud.bit_rate(500000);
    command_at(bridge, kStart, baud);
    EXPECT_EQ(sink.states_of(80), std::vector{COMMAND_REJECTED});
    EXPECT_EQ(sink.last_reason(),
              "setting the baud rate is not allowed; start the gateway with --allow-baud-change");
    EXPECT_TRUE(sent().empty());
    command_at(bridge, kStart,
               from(kEcu, 81, command(1, COMMAND_REQUEST_BAUD_RATE)));  // asking is fine
    EXPECT_EQ(sent().at(0).data[1], 0x55);
  }
  auto c = config();
  c.allow_baud_change = true;
  Bridge bridge(c, gateway_bus, sink, clock);
  announce(bridge, 0xD8, 1, kStart);
  (void)sent();
  auto baud = from(kEcu, 82, command(1, COMMAND_SET_BAUD_RATE));
  baud.bit_rate(500000);
  command_at(bridge, kStart, baud);
  const auto frames = sent();
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].data[0], 0x93);
  EXPECT_EQ(frames[0].data[1], 0xA5);
  EXPECT_EQ(frames[0].data[2], 0x01);
  deliver(bridge, from_valve(0xD8, codec::BaudRateReply{500000}, kStart + 10ms));
  EXPECT_EQ(sink.states_of(82), (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
}

TEST_F(BridgeTest, SendFailureRejectsTheCommandVisibly) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 1, kStart);
  can::VirtualBus::set_link_up(bus_name, false);
  command_at(bridge, kStart, from(kEcu, 90, stop(1)));
  EXPECT_EQ(sink.states_of(90), std::vector{COMMAND_REJECTED});
  EXPECT_EQ(sink.last_reason(), "CAN send failed: " + bus_name + ": link is down");
  can::VirtualBus::set_link_up(bus_name, true);
}

TEST_F(BridgeTest, StopAllStopsEveryOnlineValve) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xDA, 3, kStart);  // long gone by the time of the stop
  announce(bridge, 0xD8, 1, kStart + 10s);
  announce(bridge, 0xD9, 2, kStart + 10s);
  tick_at(bridge, kStart + 10s);
  (void)sent();
  EXPECT_EQ(stop_all_at(bridge, kStart + 10s), 2u);
  const auto frames = sent();
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].id, 0x18EFD8D5u);
  EXPECT_EQ(frames[1].id, 0x18EFD9D5u);
  EXPECT_EQ(frames[0].data[0], 0x00);
}

TEST_F(BridgeTest, AtShutdownEveryCommandStillFollowedEndsSayingTheGatewayStopped) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 1, kStart);
  announce(bridge, 0xD9, 2, kStart);
  command_at(bridge, kStart,
             from(kEcu, 80, move_to(1, 90.0f)));  // a move the valve is left to finish
  command_at(bridge, kStart, from(kEcu, 81, request(2, TELEMETRY_VOLTAGE)));  // awaiting its reply
  command_at(bridge, kStart, from(kEcu, 82, stop(2)));                        // over already
  (void)sent();
  EXPECT_EQ(bridge.end_all_commands(), 2u);
  EXPECT_EQ(sink.states_of(80), (std::vector{COMMAND_ACCEPTED, COMMAND_TIMED_OUT}));
  EXPECT_EQ(sink.states_of(81), (std::vector{COMMAND_ACCEPTED, COMMAND_TIMED_OUT}));
  EXPECT_EQ(sink.states_of(82), (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
  EXPECT_EQ(sink.last_reason(), "the gateway stopped before the command finished");
  EXPECT_TRUE(sent().empty()) << "nothing is sent to the valves on the way out";
  EXPECT_EQ(bridge.end_all_commands(), 0u);  // each ends once
}

TEST_F(BridgeTest, FailSafeStopsOnlyTheLostCommandersValves) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 1, kStart);
  announce(bridge, 0xD9, 2, kStart);
  command_at(bridge, kStart, from(kEcu, 100, command(1, COMMAND_MANUAL)), "writer-a");
  command_at(bridge, kStart, from(kEcu, 101, command(2, COMMAND_MANUAL)), "writer-b");
  (void)sent();
  EXPECT_EQ(stop_commanded_by_at(bridge, kStart + 1s, "writer-a"), 1u);
  const auto frames = sent();
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].id, 0x18EFD8D5u);
  EXPECT_EQ(sink.states_of(100), (std::vector{COMMAND_ACCEPTED, COMMAND_SUPERSEDED}));
  EXPECT_EQ(sink.states_of(101), std::vector{COMMAND_ACCEPTED});
}

TEST_F(BridgeTest, GatewayStatusOnceASecondStartingAfterOneIAmHerePeriod) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  tick_at(bridge, kStart);
  EXPECT_TRUE(sink.gateway_statuses().empty());  // no valve could have announced itself yet
  announce(bridge, 0xD8, 1, kStart + 300ms);
  tick_at(bridge, kStart + 999ms);
  EXPECT_TRUE(sink.gateway_statuses().empty());
  tick_at(bridge, kStart + 1s);
  tick_at(bridge, kStart + 1500ms);
  tick_at(bridge, kStart + 2s);
  ASSERT_EQ(sink.gateway_statuses().size(), 2u);
  EXPECT_EQ(sink.gateway_statuses()[0].valves_online(), 1u);
  EXPECT_EQ(sink.gateway_statuses()[0].valves_known(), 1u);
  EXPECT_EQ(sink.gateway_statuses()[0].frames_out(), 9u);
  EXPECT_EQ(sink.gateway_statuses()[0].bus_state(), BUS_ERROR_ACTIVE);
  EXPECT_EQ(sink.gateway_statuses()[1].stamp_ns(), unix_nanoseconds(kStart + 2s));
}

// Two valves with one serial on two buses (or a replay of one): a command to that serial would
// move whichever valve; each gateway lists its online serials in its status and refuses it.
TEST_F(BridgeTest, ASerialAnotherGatewayReportsOnlineIsListedAndItsCommandsRefused) {
  struct Others final : OtherGateways {
    std::vector<std::string> reporting_online(std::uint32_t serial) const override {
      if (serial == 2) return {"rig-2"};
      return {};
    }
  } others;
  Bridge bridge(config(), gateway_bus, sink, clock, &others);
  announce(bridge, 0xD8, 1, kStart);
  announce(bridge, 0xD9, 2, kStart);
  announce(bridge, 0xDA, 3, kStart);
  tick_at(bridge, kStart + 1s);
  ASSERT_EQ(sink.gateway_statuses().size(), 1u);
  EXPECT_EQ(sink.gateway_statuses()[0].serials_online(), (std::vector<std::uint32_t>{1, 2, 3}));
  (void)sent();
  command_at(bridge, kStart + 1s, from(kEcu, 7, move_to(2, 45.0f)));
  EXPECT_EQ(sink.states_of(7), std::vector{COMMAND_REJECTED});
  EXPECT_EQ(sink.last_reason(),
            "valve TJV000002 is also online on gateway rig-2: two valves carry this serial, or "
            "something replays it; commands to it but Stop are refused until only one gateway "
            "reports it");
  EXPECT_TRUE(sent().empty());
  command_at(bridge, kStart + 1s, from(kEcu, 8, move_to(1, 45.0f)));
  EXPECT_EQ(sink.states_of(8), std::vector{COMMAND_ACCEPTED});
  // A Stop is safe for both valves: each gateway stops its own.
  (void)sent();
  command_at(bridge, kStart + 1s, from(kEcu, 9, stop(2)));
  EXPECT_EQ(sink.states_of(9), (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
  EXPECT_EQ(sent().size(), 1u);
}

// The thread that takes commands keeps their deadlines but never calls a valve offline: only
// the bus reader may, once it took what the bus holds (on a starved machine the I'm Here can
// be waiting there: a command to that valve was REJECTED "offline" in a flood under ASan).
TEST_F(BridgeTest, TheCommandThreadsTickEndsCommandsButLeavesValvesToTheBusReader) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 9, kStart);
  auto jog = from(kEcu, 12, command(9, COMMAND_MILLISECONDS_TO_RUN));
  jog.milliseconds(1500);
  command_at(bridge, kStart + 1s, jog);
  EXPECT_LE(bridge.next_command_deadline(), clock->steady() + 1500ms);

  at(kStart + 4s);  // past both deadlines: the jog's end and the valve's 3 s of silence
  bridge.tick_commands();
  EXPECT_EQ(sink.states_of(12), (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
  EXPECT_TRUE(sink.presences().back().online());
  bridge.tick();
  EXPECT_FALSE(sink.presences().back().online());
}

// Issue 7, bug 7: an NTP or GPS step of the wall clock at boot took every valve offline (or
// stretched every deadline), because deadlines ran on the wall clock.
TEST_F(BridgeTest, AWallClockStepNeitherTakesValvesOfflineNorMovesDeadlines) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 1, kStart);
  auto jog = from(kEcu, 110, command(1, COMMAND_MILLISECONDS_TO_RUN));
  jog.milliseconds(1500);
  command_at(bridge, kStart, jog);

  clock->step_wall(1h);  // the date is set: an hour later on the wall, no time passed
  bridge.tick();
  EXPECT_TRUE(sink.presences().back().online());
  EXPECT_EQ(sink.states_of(110), std::vector{COMMAND_ACCEPTED});

  clock->step_wall(-2h);  // and set back again, further than it went
  clock->advance(1500ms);
  bridge.tick();
  EXPECT_EQ(sink.states_of(110), (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
  // Published stamps follow the wall clock as it is now.
  EXPECT_EQ(sink.statuses().back().stamp_ns(), unix_nanoseconds(kStart - 1h + 1500ms));
  clock->advance(1501ms);  // 3 s of steady time without I'm Here
  bridge.tick();
  EXPECT_FALSE(sink.presences().back().online());
}

// Issue 7, bug 2: when another serial took over an address, the displaced valve stayed online
// at it, so its commands went to the new occupant until it announced itself again.
TEST_F(BridgeTest, ADisplacedValvesCommandsNeverGoToTheValveThatTookItsAddress) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 2, kStart);
  announce(bridge, 0xD8, 1, kStart + 1s);  // TJV000001 joins and takes 0xD8
  const auto presences = sink.presences();
  const auto displaced = std::find_if(presences.begin(), presences.end(),
                                      [](auto& p) { return p.serial() == 2 && !p.online(); });
  ASSERT_NE(displaced, presences.end()) << "the displaced valve's presence goes offline";
  (void)sent();

  command_at(bridge, kStart + 1s, from(kEcu, 120, stop(2)));
  EXPECT_EQ(sink.states_of(120), std::vector{COMMAND_REJECTED});
  EXPECT_EQ(sink.last_reason(),
            "valve TJV000002 is offline: TJV000001 took its address 0xD8 and it has not "
            "announced its new one yet");
  EXPECT_TRUE(sent().empty()) << "nothing may reach TJV000001 on TJV000002's behalf";

  announce(bridge, 0xD9, 2, kStart + 1s + 31ms);  // it announces where it is now
  EXPECT_TRUE(sink.presences().back().online());
  (void)sent();
  command_at(bridge, kStart + 1100ms, from(kEcu, 121, stop(2)));
  EXPECT_EQ(sink.states_of(121), (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
  const auto frames = sent();
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].id, 0x18EFD9D5u);
}

TEST_F(BridgeTest, ADisplacedValveKeepsWorkingOnItsCommand) {
  // The valve did not stop because its address changed; only where to reach it did.
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 2, kStart);
  deliver(bridge, from_valve(0xD8, codec::Position{0.0}, kStart));
  command_at(bridge, kStart, from(kEcu, 130, move_to(2, 90.0f)));
  announce(bridge, 0xD8, 1, kStart + 200ms);
  announce(bridge, 0xD9, 2, kStart + 231ms);
  deliver(bridge, from_valve(0xD9, codec::Position{90.0}, kStart + 1s));
  EXPECT_EQ(sink.states_of(130), (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
}

TEST_F(BridgeTest, NextDeadlineIsTheEarliestOfStatusExpiryAndCommands) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  const SteadyTime start = clock->steady();
  EXPECT_EQ(bridge.next_deadline(), start + 1s);  // the first gateway status
  announce(bridge, 0xD8, 1, kStart);
  auto jog = from(kEcu, 140, command(1, COMMAND_MILLISECONDS_TO_RUN));
  jog.milliseconds(300);
  command_at(bridge, kStart + 100ms, jog);
  EXPECT_EQ(bridge.next_deadline(), start + 400ms);
  tick_at(bridge, kStart + 400ms);
  EXPECT_EQ(sink.states_of(140), (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
  EXPECT_EQ(bridge.next_deadline(), start + 1s);
  tick_at(bridge, kStart + 1s);  // status published; then expiry (3 s + 1 ns) is later
  EXPECT_EQ(bridge.next_deadline(), start + 2s);
}

TEST_F(BridgeTest, AValveThatGoesQuietIsNeverDeclaredOfflineLate) {
  // The deadline is kept between batches of frames; an I'm Here must not leave it too late.
  auto settings = config();
  settings.offline_after = 500ms;
  Bridge bridge(settings, gateway_bus, sink, clock);
  const SteadyTime start = clock->steady();
  announce(bridge, 0xD8, 1, kStart);
  announce(bridge, 0xD9, 2, kStart + 100ms);
  EXPECT_EQ(bridge.next_deadline(), start + 500ms + 1ns);
  announce(bridge, 0xD8, 1, kStart + 300ms);  // 1 is now due at 800 ms, 2 at 600 ms
  EXPECT_LE(bridge.next_deadline(), start + 600ms + 1ns);
  tick_at(bridge, kStart + 500ms + 1ns);  // nothing due yet: a fresh look
  EXPECT_TRUE(sink.presences().back().online());
  EXPECT_EQ(bridge.next_deadline(), start + 600ms + 1ns);
  tick_at(bridge, kStart + 600ms + 1ns);
  EXPECT_EQ(sink.presences().back().serial(), 2u);
  EXPECT_FALSE(sink.presences().back().online());
  EXPECT_EQ(bridge.next_deadline(), start + 800ms + 1ns);
}

// ---- Where each valve sits (docs/layout.md) ------------------------------------------------

layout::Layout boom_layout() {
  return *layout::Layout::make(
      {{.name = "left-master", .order = 1, .role = layout::Role::kMaster, .serial = 1},
       {.name = "section-01", .order = 2, .serial = 2, .mechanics = layout::Mechanics{10, 80}},
       {.name = "section-02", .order = 3}},
      layout::Mechanics{0, 90});
}

TEST_F(BridgeTest, EveryLocationIsPublishedAtOnceMissingOrEmpty) {
  auto c = config();
  c.layout = boom_layout();
  Bridge bridge(c, gateway_bus, sink, clock);
  const auto places = sink.latest_locations();
  ASSERT_EQ(places.size(), 3u);
  const auto& master = places.at("left-master");
  EXPECT_EQ(master.gateway().to_string(), "gw-test");
  EXPECT_EQ(master.order(), 1u);
  EXPECT_EQ(master.role(), ROLE_MASTER);
  EXPECT_TRUE(master.assigned());
  EXPECT_EQ(master.serial(), 1u);
  EXPECT_EQ(master.state(), LOCATION_MISSING);  // never seen yet
  EXPECT_TRUE(master.mechanics_known());
  EXPECT_EQ(master.opened_degrees(), 90.0f);  // the default
  const auto& section = places.at("section-01");
  EXPECT_EQ(section.role(), ROLE_SECTION);
  EXPECT_EQ(section.closed_degrees(), 10.0f);
  EXPECT_EQ(section.opened_degrees(), 80.0f);
  const auto& empty = places.at("section-02");
  EXPECT_FALSE(empty.assigned());
  EXPECT_EQ(empty.serial(), 0u);
  EXPECT_EQ(empty.state(), LOCATION_EMPTY);
}

TEST_F(BridgeTest, ALocationIsOkWhileItsValveIsOnlineAndMissingOnceItIsNot) {
  auto c = config();
  c.layout = boom_layout();
  c.offline_after = 3s;
  Bridge bridge(c, gateway_bus, sink, clock);
  announce(bridge, 0xD9, 2, kStart);
  EXPECT_EQ(sink.latest_locations().at("section-01").state(), LOCATION_OK);
  EXPECT_EQ(sink.last_presence(2)->sample.location().to_string(), "section-01");
  const auto published = sink.locations().size();
  announce(bridge, 0xD9, 2, kStart + 1s);  // nothing changed: nothing republished
  EXPECT_EQ(sink.locations().size(), published);
  tick_at(bridge, kStart + 1s + 3001ms);
  EXPECT_EQ(sink.latest_locations().at("section-01").state(), LOCATION_MISSING);
  EXPECT_EQ(sink.latest_locations().at("left-master").state(), LOCATION_MISSING);
}

TEST_F(BridgeTest, AValveInNoLocationHasNoneInItsPresence) {
  auto c = config();
  c.layout = boom_layout();
  Bridge bridge(c, gateway_bus, sink, clock);
  const auto published = sink.locations().size();
  announce(bridge, 0xDA, 17, kStart);
  EXPECT_EQ(sink.last_presence(17)->sample.location().to_string(), "");
  EXPECT_EQ(sink.locations().size(), published);
}

TEST_F(BridgeTest, WithoutALayoutNoLocationIsPublished) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD8, 1, kStart);
  EXPECT_TRUE(sink.locations().empty());
  EXPECT_EQ(sink.last_presence(1)->sample.location().to_string(), "");
}

TEST_F(BridgeTest, EveryRoleKeepsItsLayoutNameOnDds) {
  auto c = config();
  std::vector<layout::Location> places;
  for (const auto name : layout::role_names()) {
    places.push_back({.name = "place-" + std::string(name),
                      .order = static_cast<unsigned>(places.size() + 1),
                      .role = *layout::role_from(name)});
  }
  c.layout = *layout::Layout::make(places);
  Bridge bridge(c, gateway_bus, sink, clock);
  const auto published = sink.latest_locations();
  ASSERT_EQ(published.size(), layout::role_names().size());
  for (const auto name : layout::role_names()) {
    EXPECT_EQ(dds::to_string(published.at("place-" + std::string(name)).role()), name);
  }
}

// ---- Layout changes: a valve put at its place without editing files -----------------------

class MemoryLayoutStore final : public layout::LayoutStore {
 public:
  Status save(const layout::Layout& layout) override {
    if (refusal) return *refusal;
    saved.push_back(layout);
    return {};
  }
  std::vector<layout::Layout> saved;
  std::optional<Error> refusal;
};

LayoutChange layout_change(LayoutChangeKind kind, const std::string& location,
                           std::uint32_t serial = 0, bool move = false,
                           const std::string& gateway = "gw-test") {
  static std::uint32_t next_id = 1;
  LayoutChange change;
  change.location(location);
  change.gateway(gateway);
  change.change_id(next_id++);
  change.origin(kEcu);
  change.kind(kind);
  change.serial(serial);
  change.move(move);
  return change;
}

class BridgeLayoutChange : public BridgeTest {
 protected:
  BridgeConfig boom_config() {
    auto c = config();
    c.layout = boom_layout();
    return c;
  }
  // The status that answered `change`, which must be the only one for it.
  LayoutChangeStatus answer_to(const LayoutChange& change) {
    std::vector<LayoutChangeStatus> answers;
    for (const auto& status : sink.layout_statuses()) {
      if (status.change_id() == change.change_id()) answers.push_back(status);
    }
    EXPECT_EQ(answers.size(), 1u);
    return answers.empty() ? LayoutChangeStatus{} : answers.front();
  }
  MemoryLayoutStore store;
};

TEST_F(BridgeLayoutChange, AnAssignmentIsSavedThenPublishedAndAnswered) {
  Bridge bridge(boom_config(), gateway_bus, sink, clock, nullptr, &store);
  announce(bridge, 0xDB, 7, kStart);
  EXPECT_EQ(sink.last_presence(7)->sample.location().to_string(), "");
  const auto change = layout_change(LAYOUT_ASSIGN, "section-02", 7);
  bridge.on_layout_change(change);

  ASSERT_EQ(store.saved.size(), 1u);
  EXPECT_EQ(store.saved[0].find("section-02")->serial, 7u);
  EXPECT_EQ(store.saved[0], bridge.current_layout());
  const auto place = sink.latest_locations().at("section-02");
  EXPECT_EQ(place.serial(), 7u);
  EXPECT_EQ(place.state(), LOCATION_OK);
  EXPECT_EQ(sink.last_presence(7)->sample.location().to_string(), "section-02");
  const auto answer = answer_to(change);
  EXPECT_EQ(answer.state(), LAYOUT_CHANGE_APPLIED);
  EXPECT_EQ(answer.location().to_string(), "section-02");
  EXPECT_EQ(answer.gateway().to_string(), "gw-test");
  EXPECT_EQ(answer.origin().to_string(), kEcu);
  EXPECT_EQ(answer.serial(), 7u);
  EXPECT_EQ(answer.reason().to_string(), "");
}

TEST_F(BridgeLayoutChange, AReplacementTakesThePlaceOfTheOldSerialWhichSitsNowhere) {
  Bridge bridge(boom_config(), gateway_bus, sink, clock, nullptr, &store);
  announce(bridge, 0xD9, 2, kStart);
  announce(bridge, 0xDA, 9, kStart);
  const auto change = layout_change(LAYOUT_ASSIGN, "section-01", 9);
  bridge.on_layout_change(change);
  EXPECT_EQ(answer_to(change).reason().to_string(), "TJV000002 left it");
  EXPECT_EQ(sink.latest_locations().at("section-01").serial(), 9u);
  EXPECT_EQ(sink.last_presence(9)->sample.location().to_string(), "section-01");
  EXPECT_EQ(sink.last_presence(2)->sample.location().to_string(), "");
  // The place keeps its own mechanics: they belong to the place, not to the valve that left.
  EXPECT_EQ(sink.latest_locations().at("section-01").opened_degrees(), 80.0f);
}

TEST_F(BridgeLayoutChange, AMoveEmptiesThePlaceTheValveCameFrom) {
  Bridge bridge(boom_config(), gateway_bus, sink, clock, nullptr, &store);
  announce(bridge, 0xD8, 1, kStart);
  const auto refused = layout_change(LAYOUT_ASSIGN, "section-02", 1);
  bridge.on_layout_change(refused);
  EXPECT_EQ(answer_to(refused).state(), LAYOUT_CHANGE_REJECTED);
  EXPECT_EQ(answer_to(refused).reason().to_string(),
            "TJV000001 sits at left-master; unassign it there first, or move it");
  const auto moved = layout_change(LAYOUT_ASSIGN, "section-02", 1, /*move=*/true);
  bridge.on_layout_change(moved);
  EXPECT_EQ(answer_to(moved).state(), LAYOUT_CHANGE_APPLIED);
  EXPECT_EQ(answer_to(moved).reason().to_string(), "TJV000001 left left-master");
  EXPECT_EQ(sink.latest_locations().at("left-master").state(), LOCATION_EMPTY);
  EXPECT_EQ(sink.latest_locations().at("section-02").state(), LOCATION_OK);
  EXPECT_EQ(store.saved.size(), 1u);
}

TEST_F(BridgeLayoutChange, AnUnassignedPlaceIsEmptyAndItsValveSitsNowhere) {
  Bridge bridge(boom_config(), gateway_bus, sink, clock, nullptr, &store);
  announce(bridge, 0xD9, 2, kStart);
  const auto change = layout_change(LAYOUT_UNASSIGN, "section-01");
  bridge.on_layout_change(change);
  EXPECT_EQ(answer_to(change).state(), LAYOUT_CHANGE_APPLIED);
  EXPECT_EQ(answer_to(change).serial(), 0u);
  EXPECT_EQ(answer_to(change).reason().to_string(), "TJV000002 left it");
  EXPECT_EQ(sink.latest_locations().at("section-01").state(), LOCATION_EMPTY);
  EXPECT_EQ(sink.last_presence(2)->sample.location().to_string(), "");
  // Nothing to do the second time: answered, not saved again.
  const auto again = layout_change(LAYOUT_UNASSIGN, "section-01");
  bridge.on_layout_change(again);
  EXPECT_EQ(answer_to(again).state(), LAYOUT_CHANGE_APPLIED);
  EXPECT_EQ(answer_to(again).reason().to_string(), "it was empty already");
  EXPECT_EQ(store.saved.size(), 1u);
}

TEST_F(BridgeLayoutChange, RefusalsSayWhyAndChangeNothing) {
  Bridge bridge(boom_config(), gateway_bus, sink, clock, nullptr, &store);
  announce(bridge, 0xDB, 7, kStart);
  const auto published = sink.locations().size();
  const auto reason_of = [&](const LayoutChange& change) {
    bridge.on_layout_change(change);
    const auto answer = answer_to(change);
    EXPECT_EQ(answer.state(), LAYOUT_CHANGE_REJECTED);
    return answer.reason().to_string();
  };
  EXPECT_EQ(reason_of(layout_change(LAYOUT_ASSIGN, "section-09", 7)),
            "gateway gw-test's layout has no location 'section-09'");
  EXPECT_EQ(reason_of(layout_change(LAYOUT_ASSIGN, "section-02", 8)),
            "TJV000008 is not online on virtual:RefusalsSayWhyAndChangeNothing (gateway "
            "gw-test): a valve is assigned where it is fitted and announcing itself");
  store.refusal = Error{ErrorCode::kSystem, "cannot write /etc/teejet/layout.yaml: disk full"};
  EXPECT_EQ(reason_of(layout_change(LAYOUT_ASSIGN, "section-02", 7)),
            "nothing changed: cannot write /etc/teejet/layout.yaml: disk full");
  EXPECT_EQ(bridge.current_layout(), boom_layout());
  EXPECT_EQ(sink.locations().size(), published);
  EXPECT_EQ(sink.last_presence(7)->sample.location().to_string(), "");
  EXPECT_TRUE(store.saved.empty());
}

TEST_F(BridgeLayoutChange, AValveOnAnotherGatewaysBusIsAssignedThere) {
  struct Others final : OtherGateways {
    std::vector<std::string> reporting_online(std::uint32_t serial) const override {
      return serial == 7 ? std::vector<std::string>{"rig-2"} : std::vector<std::string>{};
    }
  } others;
  Bridge bridge(boom_config(), gateway_bus, sink, clock, &others, &store);
  const auto change = layout_change(LAYOUT_ASSIGN, "section-02", 7);
  bridge.on_layout_change(change);
  EXPECT_EQ(answer_to(change).reason().to_string(),
            "TJV000007 is online on the bus of gateway rig-2, not of this one: assign it there");
}

TEST_F(BridgeLayoutChange, AChangeForAnotherGatewayIsNotThisOnesToAnswer) {
  Bridge bridge(boom_config(), gateway_bus, sink, clock, nullptr, &store);
  announce(bridge, 0xDB, 7, kStart);
  bridge.on_layout_change(layout_change(LAYOUT_ASSIGN, "section-02", 7, false, "rig-2"));
  EXPECT_TRUE(sink.layout_statuses().empty());
  EXPECT_TRUE(store.saved.empty());
}

TEST_F(BridgeLayoutChange, WithoutALayoutFileChangesAreRefused) {
  Bridge bridge(boom_config(), gateway_bus, sink, clock);
  announce(bridge, 0xDB, 7, kStart);
  const auto change = layout_change(LAYOUT_ASSIGN, "section-02", 7);
  bridge.on_layout_change(change);
  EXPECT_EQ(answer_to(change).reason().to_string(),
            "nothing changed: gateway gw-test has no layout file to keep it in (started without "
            "layout_file: or --layout)");
}

TEST_F(BridgeLayoutChange, AValvePutAtAPlaceMovesWithinThatPlacesMechanics) {
  Bridge bridge(boom_config(), gateway_bus, sink, clock, nullptr, &store);
  announce(bridge, 0xDB, 7, kStart);
  // section-01 opens to 80 degrees (the default: 90): the valve stops there short of 120.
  bridge.on_layout_change(layout_change(LAYOUT_ASSIGN, "section-01", 7));
  command_at(bridge, kStart + 1s, from(kEcu, 70, move_to(7, 120.0f)));
  deliver(bridge, from_valve(0xDB, codec::Position{80.0}, kStart + 2s));
  EXPECT_EQ(sink.states_of(70), (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
  EXPECT_EQ(sink.last_reason(), "stopped at 80.0, the Opened Degrees of section-01 (asked 120.0)");
}

// ---- Moves the valve's own mechanics cut short (issue 26, item 5) ---------------------------

TEST_F(BridgeTest, AMoveAValveStopsShortOfEndsWhereItStoppedWhenItsMechanicsAreUnknown) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD9, 2, kStart);
  deliver(bridge, from_valve(0xD9, codec::Position{0.0}, kStart + 100ms));
  command_at(bridge, kStart + 200ms, from(kEcu, 71, move_to(2, 120.0f)));
  // The valve, configured 0..90, takes 120 as its Opened Degrees (the sheet) and stops there.
  deliver(bridge, from_valve(0xD9, codec::Position{60.0}, kStart + 1s));
  deliver(bridge, from_valve(0xD9, codec::Position{90.0}, kStart + 2s));
  deliver(bridge,
          from_valve(0xD9, codec::SpeedDirection{0, codec::Direction::kOpen}, kStart + 2100ms));
  deliver(bridge, from_valve(0xD9, codec::Position{90.0}, kStart + 3s));
  EXPECT_EQ(sink.states_of(71), std::vector{COMMAND_ACCEPTED});  // steady 1 s: not yet
  deliver(bridge, from_valve(0xD9, codec::Position{90.0}, kStart + 3600ms));
  EXPECT_EQ(sink.states_of(71), (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
  EXPECT_EQ(sink.last_reason(),
            "stopped at 90.0, short of the 120.0 asked, and holds there: presumably its own "
            "Opened or Closed Degrees, which the layout does not give for this valve "
            "(docs/layout.md)");
}

TEST_F(BridgeTest, AValveThatHoldsStillButStillReportsSpeedIsNotCalledStopped) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce(bridge, 0xD9, 2, kStart);
  deliver(bridge, from_valve(0xD9, codec::Position{0.0}, kStart + 100ms));
  command_at(bridge, kStart + 200ms, from(kEcu, 72, move_to(2, 120.0f, 10)));
  deliver(bridge,
          from_valve(0xD9, codec::SpeedDirection{10, codec::Direction::kOpen}, kStart + 1s));
  for (auto at = kStart + 1100ms; at < kStart + 3s; at += 100ms) {
    deliver(bridge, from_valve(0xD9, codec::Position{0.0}, at));  // starting slowly
  }
  EXPECT_EQ(sink.states_of(72), std::vector{COMMAND_ACCEPTED});
}

TEST_F(BridgeTest, AValveBlockedShortOfATargetWithinItsMechanicsTimesOutAtOnce) {
  auto c = config();
  c.layout = *layout::Layout::make({}, layout::Mechanics{0, 90});
  Bridge bridge(c, gateway_bus, sink, clock);
  announce(bridge, 0xD9, 2, kStart);
  deliver(bridge, from_valve(0xD9, codec::Position{0.0}, kStart + 100ms));
  command_at(bridge, kStart + 200ms, from(kEcu, 73, move_to(2, 60.0f)));
  deliver(bridge, from_valve(0xD9, codec::Position{30.0}, kStart + 1s));
  deliver(bridge,
          from_valve(0xD9, codec::SpeedDirection{0, codec::Direction::kOpen}, kStart + 1100ms));
  deliver(bridge, from_valve(0xD9, codec::Position{30.1}, kStart + 2s));
  deliver(bridge, from_valve(0xD9, codec::Position{30.1}, kStart + 2600ms));
  EXPECT_EQ(sink.states_of(73), (std::vector{COMMAND_ACCEPTED, COMMAND_TIMED_OUT}));
  EXPECT_EQ(sink.last_reason(),
            "stopped at 30.1, short of the 60.0 asked, and holds there (speed 0): blocked, or its "
            "mechanics are not these");
}

}  // namespace
}  // namespace teejet::bridge
