// Everything a simulated valve says: replies to every request with exact values, automatic
// resends, I'm Here, run time, cycle counts, current, baud rate and latched errors.

#include <gtest/gtest.h>

#include <stdexcept>

#include "sim_test_support.hpp"
#include "teejet/codec/table.hpp"
#include "teejet/sim/simulated_valve.hpp"

namespace teejet::sim::testing {
namespace {

using codec::Direction;
using codec::Rotation;

ValveConfig described_valve() {
  ValveConfig config;
  config.serial = 123456;
  config.part_number = 0x0A0B0C;
  config.degrees_per_second = 120.0;
  config.opened_degrees = 90.0;
  config.start_degrees = 45.0;
  config.opening_direction = Rotation::kCounterclockwise;
  config.application_version = {1, 2, 'e'};
  config.bootloader_version = {3, 4, 0};
  config.volts = 12.6;
  config.valve_temperature_c = -5;
  config.sensor_temperature_c = 31;
  config.running_amps = 0.8;
  return config;
}

TEST(SimValveRequests, EveryRequestIsAnsweredAtOnceWithTheConfiguredValues) {
  SimulatedValve valve(described_valve());
  const auto now = at_ms(0);
  EXPECT_EQ(only<codec::VersionInfo>(valve.handle(codec::RequestVersion{}, now)),
            (codec::VersionInfo{{1, 2, 'e'}, {3, 4, 0}}));
  EXPECT_EQ(only<codec::Position>(valve.handle(codec::RequestPosition{0}, now)),
            codec::Position{45.0});
  EXPECT_EQ(only<codec::Temperature>(valve.handle(codec::RequestTemperature{0}, now)),
            (codec::Temperature{-5, 31}));
  EXPECT_EQ(only<codec::Voltage>(valve.handle(codec::RequestVoltage{0}, now)),
            codec::Voltage{12.6});
  EXPECT_EQ(only<codec::RunCurrent>(valve.handle(codec::RequestCurrent{0}, now)),
            (codec::RunCurrent{0.0, 0.0}));
  EXPECT_EQ(only<codec::DegreesPerSecond>(valve.handle(codec::RequestDegreesPerSecond{0}, now)),
            (codec::DegreesPerSecond{120, Direction::kClose}));
  EXPECT_EQ(only<codec::SpeedDirection>(valve.handle(codec::RequestSpeedDirection{0}, now)),
            (codec::SpeedDirection{0, Direction::kClose, Rotation::kCounterclockwise}));
  EXPECT_EQ(only<codec::RunTime>(valve.handle(codec::RequestRunTime{0}, now)), codec::RunTime{0});
  EXPECT_EQ(only<codec::CycleCounts>(valve.handle(codec::RequestCycleCounts{0}, now)),
            codec::CycleCounts{0});
  EXPECT_EQ(only<codec::BaudRateReply>(
                valve.handle(codec::BaudRate{codec::BaudAction::kRequest, 250000}, now)),
            codec::BaudRateReply{250000});
}

TEST(SimValveRequests, MotionCommandsStopAndClearErrorsAreNotAnswered) {
  SimulatedValve valve(described_valve());
  EXPECT_TRUE(valve.handle(codec::Manual{10, Direction::kOpen}, at_ms(0)).empty());
  EXPECT_TRUE(
      valve.handle(codec::TargetDegrees{10, codec::TargetDirection::kOpen, 1.0}, at_ms(1)).empty());
  EXPECT_TRUE(
      valve.handle(codec::DegreesFromPosition{10, Direction::kOpen, 1.0}, at_ms(2)).empty());
  EXPECT_TRUE(valve.handle(codec::MillisecondsToRun{10, Direction::kOpen, 1}, at_ms(3)).empty());
  EXPECT_TRUE(valve.handle(codec::Stop{}, at_ms(4)).empty());
  EXPECT_TRUE(valve.handle(codec::ClearErrors{}, at_ms(5)).empty());
}

TEST(SimValveRequests, SpeedDirectionCurrentAndDegreesPerSecondFollowTheMotion) {
  SimulatedValve valve(described_valve());  // 120 dps, starts at 45
  valve.handle(codec::Manual{50, Direction::kOpen}, at_ms(0));
  EXPECT_EQ(only<codec::SpeedDirection>(valve.handle(codec::RequestSpeedDirection{0}, at_ms(100))),
            (codec::SpeedDirection{50, Direction::kOpen, Rotation::kCounterclockwise}));
  // Actual current scales with the speed; the last running current is measured at 100 % only.
  EXPECT_EQ(only<codec::RunCurrent>(valve.handle(codec::RequestCurrent{0}, at_ms(100))),
            (codec::RunCurrent{0.4, 0.0}));
  EXPECT_EQ(
      only<codec::DegreesPerSecond>(valve.handle(codec::RequestDegreesPerSecond{0}, at_ms(100))),
      (codec::DegreesPerSecond{120, Direction::kOpen}));
  valve.handle(codec::TargetDegrees{100, codec::TargetDirection::kOpen, 0.0}, at_ms(200));
  EXPECT_EQ(only<codec::RunCurrent>(valve.handle(codec::RequestCurrent{0}, at_ms(300))),
            (codec::RunCurrent{0.8, 0.8}));
  // Stopped: speed 0, the direction of the last command stays, the last current is kept.
  EXPECT_EQ(only<codec::SpeedDirection>(valve.handle(codec::RequestSpeedDirection{0}, at_ms(5000))),
            (codec::SpeedDirection{0, Direction::kClose, Rotation::kCounterclockwise}));
  EXPECT_EQ(only<codec::RunCurrent>(valve.handle(codec::RequestCurrent{0}, at_ms(5000))),
            (codec::RunCurrent{0.0, 0.8}));
}

TEST(SimValveRequests, RunTimeCountsOnlyWhileDrivenAndReportsWholeSeconds) {
  SimulatedValve valve(limited_valve(0.0));
  valve.handle(codec::Manual{100, Direction::kOpen}, at_ms(0));  // 1 s to Opened
  EXPECT_EQ(only<codec::RunTime>(valve.handle(codec::RequestRunTime{0}, at_ms(999))).seconds, 0u);
  EXPECT_EQ(only<codec::RunTime>(valve.handle(codec::RequestRunTime{0}, at_ms(60'000))).seconds,
            1u);
  valve.handle(codec::Manual{50, Direction::kClose}, at_ms(60'000));  // 2 s to Closed
  EXPECT_EQ(only<codec::RunTime>(valve.handle(codec::RequestRunTime{0}, at_ms(61'500))).seconds,
            2u);  // 1 + 1.5
  EXPECT_DOUBLE_EQ(valve.run_time_seconds(at_ms(61'500)), 2.5);
  EXPECT_EQ(only<codec::RunTime>(valve.handle(codec::RequestRunTime{0}, at_ms(90'000))).seconds,
            3u);
}

TEST(SimValveRequests, CycleCountsIncrementPerRunCommand) {
  SimulatedValve valve(limited_valve(0.0));
  valve.handle(codec::Manual{100, Direction::kOpen}, at_ms(0));
  valve.handle(codec::TargetDegrees{50, codec::TargetDirection::kOpen, 10.0}, at_ms(10));
  valve.handle(codec::DegreesFromPosition{50, Direction::kOpen, 10.0}, at_ms(20));
  valve.handle(codec::MillisecondsToRun{50, Direction::kOpen, 10}, at_ms(30));
  valve.handle(codec::Stop{}, at_ms(40));
  valve.handle(codec::Manual{0, Direction::kOpen}, at_ms(50));
  valve.handle(codec::ClearErrors{}, at_ms(60));
  EXPECT_EQ(only<codec::CycleCounts>(valve.handle(codec::RequestCycleCounts{0}, at_ms(70))).count,
            4u);
}

TEST(SimValveRequests, RequestVersionIsAnsweredOnceOnly) {
  SimulatedValve valve(described_valve());
  EXPECT_EQ(valve.handle(codec::RequestVersion{}, at_ms(0)).size(), 1u);
  EXPECT_FALSE(valve.next_due());
  EXPECT_TRUE(valve.advance(at_ms(10'000)).empty());
}

// ---- Automatic resend --------------------------------------------------------------------

TEST(SimValveRequests, ResendEveryNTenthsUntilChanged) {
  SimulatedValve valve(limited_valve(0.0));
  EXPECT_EQ(valve.handle(codec::RequestPosition{5}, at_ms(0)).size(), 1u);  // at once
  EXPECT_EQ(valve.resend_period(0x11), std::optional<Duration>(500ms));
  EXPECT_EQ(valve.next_due(), std::optional(at_ms(500)));
  EXPECT_TRUE(valve.advance(at_ms(499)).empty());
  EXPECT_EQ(only<codec::Position>(valve.advance(at_ms(500))), codec::Position{0.0});
  EXPECT_TRUE(valve.advance(at_ms(999)).empty());
  EXPECT_EQ(valve.advance(at_ms(1000)).size(), 1u);
  EXPECT_EQ(valve.next_due(), std::optional(at_ms(1500)));
}

TEST(SimValveRequests, ANewRequestOfTheSameKindReplacesThePeriod) {
  SimulatedValve valve(limited_valve(0.0));
  valve.handle(codec::RequestPosition{5}, at_ms(0));
  EXPECT_EQ(valve.handle(codec::RequestPosition{2}, at_ms(350)).size(), 1u);  // at once
  EXPECT_TRUE(valve.advance(at_ms(500)).empty());  // the old 0.5 s rhythm is gone
  EXPECT_TRUE(valve.advance(at_ms(549)).empty());
  EXPECT_EQ(valve.advance(at_ms(550)).size(), 1u);  // 350 + 200
  EXPECT_EQ(valve.advance(at_ms(750)).size(), 1u);
  // Zero: answered once more and the resend stops.
  EXPECT_EQ(valve.handle(codec::RequestPosition{0}, at_ms(800)).size(), 1u);
  EXPECT_FALSE(valve.resend_period(0x11));
  EXPECT_FALSE(valve.next_due());
  EXPECT_TRUE(valve.advance(at_ms(5000)).empty());
}

TEST(SimValveRequests, EachKindResendsOnItsOwnPeriod) {
  SimulatedValve valve(limited_valve(0.0));
  valve.handle(codec::RequestPosition{1}, at_ms(0));
  valve.handle(codec::RequestVoltage{3}, at_ms(0));
  valve.handle(codec::RequestCycleCounts{10}, at_ms(0));
  int positions = 0;
  int voltages = 0;
  int counts = 0;
  for (int ms = 10; ms <= 1000; ms += 10) {
    for (const auto& message : valve.advance(at_ms(ms))) {
      positions += std::holds_alternative<codec::Position>(message);
      voltages += std::holds_alternative<codec::Voltage>(message);
      counts += std::holds_alternative<codec::CycleCounts>(message);
    }
  }
  EXPECT_EQ(positions, 10);
  EXPECT_EQ(voltages, 3);
  EXPECT_EQ(counts, 1);
}

// Every telemetry request of the codec's table is answered with the reply the table names,
// and the ones with automatic resend resend it.
TEST(SimValveRequests, EveryTelemetryRequestOfTheTableIsAnsweredAndResent) {
  for (const std::string_view name : codec::telemetry_names()) {
    SimulatedValve each(limited_valve(0.0));
    auto request = *codec::telemetry_request(name);
    const auto& described = codec::describe(request);
    const bool resends = codec::set_field(request, "resend_tenths", std::int64_t{1}).ok();
    const auto replies = each.handle(request, at_ms(0));
    ASSERT_EQ(replies.size(), 1u) << name;
    EXPECT_EQ(codec::message_id(replies.front()), described.reply) << name;
    if (!resends) {
      EXPECT_FALSE(each.next_due()) << name;
      continue;
    }
    EXPECT_EQ(each.resend_period(described.id), std::optional<Duration>(100ms)) << name;
    const auto resent = each.advance(at_ms(100));
    ASSERT_EQ(resent.size(), 1u) << name;
    EXPECT_EQ(resent.front(), each.reply_to(request, at_ms(100))) << name;
  }
}

TEST(SimValveRequests, ResentPositionsTrackAMove) {
  SimulatedValve valve(limited_valve(0.0));
  valve.handle(codec::RequestPosition{1}, at_ms(0));
  valve.handle(codec::TargetDegrees{100, codec::TargetDirection::kOpen, 90.0}, at_ms(0));
  for (int tenth = 1; tenth <= 12; ++tenth) {
    const double expected = std::min(9.0 * tenth, 90.0);
    EXPECT_EQ(only<codec::Position>(valve.advance(at_ms(100 * tenth))), codec::Position{expected});
  }
}

TEST(SimValveRequests, ALateAdvanceSendsOnceAndKeepsThePhase) {
  SimulatedValve valve(limited_valve(0.0));
  valve.handle(codec::RequestTemperature{1}, at_ms(0));
  EXPECT_EQ(valve.advance(at_ms(1050)).size(), 1u);  // ten were due: one is sent
  EXPECT_EQ(valve.next_due(), std::optional(at_ms(1100)));
}

// ---- I'm Here ----------------------------------------------------------------------------

TEST(SimValveRequests, IAmHereOnceASecondFromTheScheduledInstant) {
  SimulatedValve valve(described_valve());
  EXPECT_TRUE(valve.advance(at_ms(0)).empty());  // no address yet, no I'm Here
  valve.schedule_i_am_here(at_ms(250));
  EXPECT_TRUE(valve.advance(at_ms(249)).empty());
  EXPECT_EQ(only<codec::IAmHere>(valve.advance(at_ms(250))),
            (codec::IAmHere{0x0A0B0C, 123456, false}));
  EXPECT_TRUE(valve.advance(at_ms(1249)).empty());
  EXPECT_EQ(valve.advance(at_ms(1250)).size(), 1u);
  EXPECT_EQ(valve.advance(at_ms(2250)).size(), 1u);
  EXPECT_EQ(valve.next_due(), std::optional(at_ms(3250)));
}

// ---- Baud rate ---------------------------------------------------------------------------

TEST(SimValveRequests, BaudRateIsReportedAndSet) {
  ValveConfig config = limited_valve();
  config.bit_rate = codec::kBitRate500k;
  SimulatedValve valve(config);
  using codec::BaudAction;
  EXPECT_EQ(only<codec::BaudRateReply>(
                valve.handle(codec::BaudRate{BaudAction::kRequest, 250000}, at_ms(0))),
            codec::BaudRateReply{500000});
  EXPECT_EQ(
      only<codec::BaudRateReply>(valve.handle(codec::BaudRate{BaudAction::kSet, 250000}, at_ms(1))),
      codec::BaudRateReply{250000});
  EXPECT_EQ(valve.bit_rate(), 250000u);
  EXPECT_EQ(only<codec::BaudRateReply>(
                valve.handle(codec::BaudRate{BaudAction::kRequest, 500000}, at_ms(2))),
            codec::BaudRateReply{250000});
}

// ---- Errors ------------------------------------------------------------------------------

class SimValveErrors : public ::testing::TestWithParam<InjectedError> {};

TEST_P(SimValveErrors, LatchedSentAtOnceRepeatedEverySecondUntilClearErrors) {
  const auto& error = GetParam();
  const std::vector<codec::FromValveMessage> expected{error};
  SimulatedValve valve(limited_valve());
  valve.inject_error(error, at_ms(100));
  EXPECT_TRUE(valve.error_latched(codec::error_kind(error)));
  EXPECT_TRUE(valve.advance(at_ms(99)).empty());
  EXPECT_EQ(valve.advance(at_ms(100)), expected);
  EXPECT_TRUE(valve.advance(at_ms(1099)).empty());
  EXPECT_EQ(valve.advance(at_ms(1100)), expected);
  EXPECT_EQ(valve.advance(at_ms(2100)), expected);
  valve.handle(codec::ClearErrors{}, at_ms(2500));
  EXPECT_FALSE(valve.error_latched(codec::error_kind(error)));
  EXPECT_FALSE(valve.next_due());
  EXPECT_TRUE(valve.advance(at_ms(10'000)).empty());
}

INSTANTIATE_TEST_SUITE_P(EachOfTheSix, SimValveErrors,
                         ::testing::Values(InjectedError{codec::HighVoltageError{16.2, 15.5}},
                                           InjectedError{codec::LowVoltageError{9.1, 10.0}},
                                           InjectedError{codec::HighCurrentError{2.35, 2.0}},
                                           InjectedError{codec::LowCurrentError{0.05, 0.1}},
                                           InjectedError{codec::HighTemperatureError{95, 85}},
                                           InjectedError{codec::MinDegreesPerSecondError{
                                               20, 30, Direction::kClose}}),
                         [](const ::testing::TestParamInfo<InjectedError>& param) {
                           return std::string(codec::error_kind(param.param));
                         });

TEST(SimValveRequests, SeveralErrorsAreLatchedTogetherAndReinjectingReplacesTheValues) {
  SimulatedValve valve(limited_valve());
  valve.inject_error(codec::HighVoltageError{16.2, 15.5}, at_ms(0));
  valve.inject_error(codec::HighTemperatureError{90, 85}, at_ms(0));
  EXPECT_EQ(valve.advance(at_ms(0)).size(), 2u);
  valve.inject_error(codec::HighVoltageError{16.4, 15.5}, at_ms(300));
  EXPECT_EQ(valve.advance(at_ms(300)),
            (std::vector<codec::FromValveMessage>{codec::HighVoltageError{16.4, 15.5}}));
  EXPECT_EQ(valve.advance(at_ms(1000)).size(), 1u);  // temperature, on its own rhythm
  EXPECT_EQ(valve.advance(at_ms(1300)),
            (std::vector<codec::FromValveMessage>{codec::HighVoltageError{16.4, 15.5}}));
}

TEST(SimValveRequests, ErrorsDoNotStopTheValveClearErrorsDoes) {
  SimulatedValve valve(limited_valve(0.0));
  valve.handle(codec::Manual{100, codec::Direction::kOpen}, at_ms(0));
  valve.inject_error(codec::HighCurrentError{2.5, 2.0}, at_ms(100));
  EXPECT_TRUE(valve.running(at_ms(200)));
  valve.handle(codec::ClearErrors{}, at_ms(200));
  EXPECT_FALSE(valve.running(at_ms(200)));
}

TEST(SimValveRequests, ValuesOutsideTheMessageAreRefused) {
  SimulatedValve valve(limited_valve());
  EXPECT_THROW(valve.inject_error(codec::HighTemperatureError{200, 85}, at_ms(0)),
               std::invalid_argument);
  EXPECT_THROW(valve.inject_error(codec::HighCurrentError{700, 2}, at_ms(0)),
               std::invalid_argument);
  EXPECT_THROW(valve.inject_error(codec::Position{45.0}, at_ms(0)), std::invalid_argument);
  EXPECT_FALSE(valve.next_due());
}

TEST(SimValveRequests, ErrorsAreMadeFromTheCodecsWordsAndChecked) {
  EXPECT_EQ(*make_error("high_voltage", 16.2, 15.5),
            (InjectedError{codec::HighVoltageError{16.2, 15.5}}));
  EXPECT_EQ(*make_error("min-dps", 20, 30, "close"),
            (InjectedError{codec::MinDegreesPerSecondError{20, 30, Direction::kClose}}));
  EXPECT_EQ(make_error("min_degrees_per_second", 20.5, 30).error().reason,
            "min_degrees_per_second_error: dps 20.5 is not a whole number");
  EXPECT_EQ(make_error("high_temperature", 200, 85).error().reason,
            "high_temperature_error: temperature_c 200 is outside 0 to 127");
  EXPECT_EQ(make_error("high_voltage", 16, 15, "open").error().reason,
            "high_voltage takes no DIRECTION");
  EXPECT_FALSE(make_error("sparks", 1, 2));
}

}  // namespace
}  // namespace teejet::sim::testing
