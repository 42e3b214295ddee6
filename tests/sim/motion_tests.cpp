// Motion of a simulated valve, command by command, with exact positions at given times.
// Defaults: 90 degrees per second at 100 %, Closed 0, Opened 90 (limited) or 360 (full turn).

#include <gtest/gtest.h>

#include "sim_test_support.hpp"
#include "teejet/sim/simulated_valve.hpp"

namespace teejet::sim::testing {
namespace {

using codec::Direction;
using codec::TargetDirection;

constexpr auto kOpen = Direction::kOpen;
constexpr auto kClose = Direction::kClose;

// ---- Limited valve ------------------------------------------------------------------------

TEST(SimValveMotion, TargetDegreesMovesAtTheConfiguredSpeedAndStopsThere) {
  SimulatedValve valve(limited_valve(0.0));
  EXPECT_TRUE(
      valve.handle(codec::TargetDegrees{100, TargetDirection::kOpen, 90.0}, at_ms(0)).empty());
  EXPECT_TRUE(valve.running(at_ms(0)));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(100)), 9.0);
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(500)), 45.0);
  EXPECT_TRUE(valve.running(at_ms(999)));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(1000)), 90.0);
  EXPECT_FALSE(valve.running(at_ms(1000)));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(5000)), 90.0);
  EXPECT_DOUBLE_EQ(valve.run_time_seconds(at_ms(5000)), 1.0);
}

TEST(SimValveMotion, SpeedPercentScalesTheDegreesPerSecond) {
  for (const auto& [speed, expected_at_400ms] :
       {std::pair{100u, 36.0}, {50u, 18.0}, {25u, 9.0}, {1u, 0.36}}) {
    SimulatedValve valve(limited_valve(0.0));
    valve.handle(codec::TargetDegrees{speed, TargetDirection::kOpen, 90.0}, at_ms(0));
    EXPECT_NEAR(valve.position(at_ms(400)), expected_at_400ms, 1e-9) << speed << " %";
  }
  ValveConfig fast = limited_valve(0.0);
  fast.degrees_per_second = 180.0;
  SimulatedValve valve(fast);
  valve.handle(codec::TargetDegrees{50, TargetDirection::kOpen, 90.0}, at_ms(0));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(500)), 45.0);
  EXPECT_FALSE(valve.running(at_ms(1000)));
}

TEST(SimValveMotion, LimitedTargetIsClampedToClosedAndOpenedDegrees) {
  ValveConfig config = limited_valve(50.0);
  config.closed_degrees = 10.0;
  config.opened_degrees = 80.0;
  SimulatedValve valve(config);
  valve.handle(codec::TargetDegrees{100, TargetDirection::kOpen, 200.0}, at_ms(0));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(5000)), 80.0);
  EXPECT_NEAR(valve.run_time_seconds(at_ms(5000)), 30.0 / 90.0, 1e-9);
  valve.handle(codec::TargetDegrees{100, TargetDirection::kClose, 0.0}, at_ms(5000));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(10000)), 10.0);
}

TEST(SimValveMotion, LimitedValvePicksTheDirectionFromTargetVersusPosition) {
  SimulatedValve valve(limited_valve(60.0));
  // The direction byte says open and shortest; the target lies below: the valve closes.
  valve.handle(codec::TargetDegrees{100, TargetDirection::kOpen, 30.0}, at_ms(0));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(100)), 51.0);
  EXPECT_EQ(valve.direction(), kClose);
  valve.handle(codec::TargetDegrees{100, TargetDirection::kShortest, 70.0}, at_ms(1000));
  EXPECT_EQ(valve.direction(), kOpen);
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(1100)), 39.0);
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(2000)), 70.0);
}

TEST(SimValveMotion, ManualRunsUntilTheLimitOnALimitedValve) {
  SimulatedValve valve(limited_valve(0.0));
  valve.handle(codec::Manual{100, kOpen}, at_ms(0));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(500)), 45.0);
  EXPECT_TRUE(valve.running(at_ms(999)));
  EXPECT_FALSE(valve.running(at_ms(1000)));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(3000)), 90.0);
  valve.handle(codec::Manual{50, kClose}, at_ms(3000));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(4000)), 45.0);
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(9000)), 0.0);
  EXPECT_DOUBLE_EQ(valve.run_time_seconds(at_ms(9000)), 3.0);
}

TEST(SimValveMotion, ManualAtALimitDoesNotMoveButCountsACycle) {
  SimulatedValve valve(limited_valve(90.0));
  valve.handle(codec::Manual{100, kOpen}, at_ms(0));
  EXPECT_FALSE(valve.running(at_ms(0)));
  EXPECT_DOUBLE_EQ(valve.position(at_ms(1000)), 90.0);
  EXPECT_EQ(valve.cycle_count(), 1u);
}

TEST(SimValveMotion, DegreesFromPositionIsAddedWhenOpeningAndStopsAtTheLimits) {
  SimulatedValve valve(limited_valve(30.0));
  valve.handle(codec::DegreesFromPosition{100, kOpen, 40.0}, at_ms(0));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(200)), 48.0);
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(1000)), 70.0);
  valve.handle(codec::DegreesFromPosition{100, kOpen, 40.0}, at_ms(1000));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(3000)), 90.0);  // 110 clamped to Opened
  valve.handle(codec::DegreesFromPosition{100, kClose, 30.5}, at_ms(3000));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(4000)), 59.5);
  valve.handle(codec::DegreesFromPosition{100, kClose, 300.0}, at_ms(4000));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(9000)), 0.0);  // clamped to Closed
}

TEST(SimValveMotion, MillisecondsToRunRunsForThatTimeOrUntilALimit) {
  SimulatedValve valve(limited_valve(0.0));
  valve.handle(codec::MillisecondsToRun{100, kOpen, 500}, at_ms(0));
  EXPECT_TRUE(valve.running(at_ms(499)));
  EXPECT_FALSE(valve.running(at_ms(500)));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(250)), 22.5);
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(2000)), 45.0);
  EXPECT_DOUBLE_EQ(valve.run_time_seconds(at_ms(2000)), 0.5);
  // 2 s at 100 % would be 180°: the valve stops at Opened after 0.5 s more.
  valve.handle(codec::MillisecondsToRun{100, kOpen, 2000}, at_ms(2000));
  EXPECT_FALSE(valve.running(at_ms(2500)));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(4000)), 90.0);
  EXPECT_DOUBLE_EQ(valve.run_time_seconds(at_ms(4000)), 1.0);
  valve.handle(codec::MillisecondsToRun{10, kClose, 65535}, at_ms(4000));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(5000)), 81.0);
}

TEST(SimValveMotion, ANewCommandReplacesTheRunningOne) {
  SimulatedValve valve(limited_valve(0.0));
  valve.handle(codec::TargetDegrees{100, TargetDirection::kOpen, 90.0}, at_ms(0));
  valve.handle(codec::TargetDegrees{100, TargetDirection::kOpen, 0.0}, at_ms(500));  // at 45
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(750)), 22.5);
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(1000)), 0.0);
  EXPECT_FALSE(valve.running(at_ms(1000)));
  valve.handle(codec::Manual{100, kOpen}, at_ms(2000));
  valve.handle(codec::MillisecondsToRun{50, kClose, 200}, at_ms(2400));  // at 36
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(2600)), 27.0);
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(5000)), 27.0);
  EXPECT_EQ(valve.cycle_count(), 4u);
  EXPECT_DOUBLE_EQ(valve.run_time_seconds(at_ms(5000)), 1.6);
}

TEST(SimValveMotion, StopAndSpeedZeroStopWhereTheValveIs) {
  SimulatedValve valve(limited_valve(0.0));
  valve.handle(codec::TargetDegrees{100, TargetDirection::kOpen, 90.0}, at_ms(0));
  valve.handle(codec::Stop{}, at_ms(300));
  EXPECT_FALSE(valve.running(at_ms(300)));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(2000)), 27.0);
  valve.handle(codec::Manual{100, kOpen}, at_ms(2000));
  valve.handle(codec::Manual{0, kOpen}, at_ms(2100));  // speed 0 = stop
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(3000)), 36.0);
  valve.handle(codec::Manual{100, kOpen}, at_ms(3000));
  valve.handle(codec::TargetDegrees{0, TargetDirection::kOpen, 90.0}, at_ms(3100));
  valve.handle(codec::Manual{100, kClose}, at_ms(4000));
  valve.handle(codec::DegreesFromPosition{0, kOpen, 10.0}, at_ms(4100));
  valve.handle(codec::Manual{100, kClose}, at_ms(5000));
  valve.handle(codec::MillisecondsToRun{0, kOpen, 1000}, at_ms(5100));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(6000)), 27.0);
  EXPECT_FALSE(valve.running(at_ms(6000)));
  EXPECT_EQ(valve.cycle_count(), 5u);  // speed-0 commands are stops, not runs
}

TEST(SimValveMotion, ClearErrorsStopsTheValve) {
  SimulatedValve valve(limited_valve(0.0));
  valve.handle(codec::Manual{100, kOpen}, at_ms(0));
  valve.handle(codec::ClearErrors{}, at_ms(200));
  EXPECT_FALSE(valve.running(at_ms(200)));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(1000)), 18.0);
}

TEST(SimValveMotion, SpeedAboveOneHundredPercentIsTreatedAsOneHundred) {
  SimulatedValve valve(limited_valve(0.0));
  valve.handle(codec::Manual{250, kOpen}, at_ms(0));  // decoded faithfully, driven at most 100 %
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(500)), 45.0);
  EXPECT_EQ(valve.speed_percent(at_ms(500)), 100u);
}

// ---- Full-turn (360-degree) valve -----------------------------------------------------------

TEST(SimValveMotion, FullTurnTargetOpenWrapsThroughZero) {
  SimulatedValve valve(full_turn_valve(350.0));
  valve.handle(codec::TargetDegrees{100, TargetDirection::kOpen, 10.0}, at_ms(0));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(100)), 359.0);
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(200)), 8.0);
  EXPECT_TRUE(valve.running(at_ms(222)));
  EXPECT_FALSE(valve.running(at_ms(223)));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(1000)), 10.0);
  EXPECT_EQ(valve.direction(), kOpen);
}

TEST(SimValveMotion, FullTurnTargetHonoursOpenAndCloseTheLongWayRound) {
  SimulatedValve valve(full_turn_valve(10.0));
  valve.handle(codec::TargetDegrees{100, TargetDirection::kOpen, 350.0}, at_ms(0));  // +340
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(1000)), 100.0);
  EXPECT_TRUE(valve.running(at_ms(3777)));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(4000)), 350.0);
  valve.handle(codec::TargetDegrees{100, TargetDirection::kClose, 0.0}, at_ms(4000));  // -350
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(5000)), 260.0);
  EXPECT_EQ(valve.direction(), kClose);
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(9000)), 0.0);
}

TEST(SimValveMotion, FullTurnShortestPathPicksTheNearerWayAndOpensOnATie) {
  SimulatedValve valve(full_turn_valve(10.0));
  valve.handle(codec::TargetDegrees{100, TargetDirection::kShortest, 350.0}, at_ms(0));
  EXPECT_EQ(valve.direction(), kClose);
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(100)), 1.0);
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(200)), 352.0);
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(1000)), 350.0);
  valve.handle(codec::TargetDegrees{100, TargetDirection::kShortest, 20.0}, at_ms(1000));
  EXPECT_EQ(valve.direction(), kOpen);
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(2000)), 20.0);
  valve.handle(codec::TargetDegrees{100, TargetDirection::kShortest, 200.0}, at_ms(2000));
  EXPECT_EQ(valve.direction(), kOpen);  // 180 either way
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(3000)), 110.0);
}

TEST(SimValveMotion, FullTurnTargetAtThePositionDoesNotTurnAFullCircle) {
  SimulatedValve valve(full_turn_valve(45.0));
  valve.handle(codec::TargetDegrees{100, TargetDirection::kOpen, 45.0}, at_ms(0));
  EXPECT_FALSE(valve.running(at_ms(0)));
  EXPECT_EQ(valve.cycle_count(), 1u);
}

TEST(SimValveMotion, FullTurnManualRunsUntilStoppedAndWraps) {
  SimulatedValve valve(full_turn_valve(0.0));
  valve.handle(codec::Manual{100, kOpen}, at_ms(0));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(5000)), 90.0);  // 450
  EXPECT_TRUE(valve.running(at_ms(60'000)));
  valve.handle(codec::Stop{}, at_ms(6000));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(7000)), 180.0);
  valve.handle(codec::Manual{50, kClose}, at_ms(7000));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(13000)), 270.0);  // 180 - 270
  EXPECT_DOUBLE_EQ(valve.run_time_seconds(at_ms(13000)), 12.0);
}

TEST(SimValveMotion, FullTurnDegreesFromPositionHasNoLimitChecking) {
  SimulatedValve valve(full_turn_valve(100.0));
  valve.handle(codec::DegreesFromPosition{100, kClose, 300.0}, at_ms(0));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(2000)), 280.0);
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(5000)), 160.0);
  valve.handle(codec::DegreesFromPosition{100, kOpen, 359.9}, at_ms(5000));
  EXPECT_TRUE(valve.running(at_ms(8998)));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(10000)), 159.9);
}

TEST(SimValveMotion, FullTurnMillisecondsToRunWraps) {
  SimulatedValve valve(full_turn_valve(300.0));
  valve.handle(codec::MillisecondsToRun{100, kOpen, 2000}, at_ms(0));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(1000)), 30.0);
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(3000)), 120.0);
  EXPECT_FALSE(valve.running(at_ms(2000)));
}

TEST(SimValveMotion, ClosedDegreesOfAFullTurnValveIsNoLimit) {
  ValveConfig config = full_turn_valve(20.0);
  config.closed_degrees = 10.0;
  SimulatedValve valve(config);
  valve.handle(codec::DegreesFromPosition{100, kClose, 30.0}, at_ms(0));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(1000)), 350.0);
}

// ---- Opening direction --------------------------------------------------------------------

TEST(SimValveMotion, OpeningDirectionChangesOnlyTheReportedSenseNotTheDegrees) {
  ValveConfig config = limited_valve(0.0);
  config.opening_direction = codec::Rotation::kCounterclockwise;
  SimulatedValve valve(config);
  valve.handle(codec::Manual{100, kOpen}, at_ms(0));
  EXPECT_DOUBLE_EQ(reported_position(valve, at_ms(500)), 45.0);
  const auto report =
      only<codec::SpeedDirection>(valve.handle(codec::RequestSpeedDirection{0}, at_ms(500)));
  EXPECT_EQ(report, (codec::SpeedDirection{100, kOpen, codec::Rotation::kCounterclockwise}));
}

}  // namespace
}  // namespace teejet::sim::testing
