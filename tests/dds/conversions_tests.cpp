#include <gtest/gtest.h>

#include "teejet/dds/conversions.hpp"
#include "teejet/dds/names.hpp"
#include "teejet/dds/participant.hpp"

namespace teejet::dds {
namespace {

constexpr Timestamp kReceived{Duration{1'700'000'000'123'456'789}};

template <class Sample>
Sample sample_of(const codec::FromValveMessage& message) {
  auto sample = to_sample(4711, message, kReceived);
  EXPECT_TRUE(sample.has_value());
  auto typed = std::get<Sample>(*sample);
  EXPECT_EQ(typed.serial(), 4711u);
  EXPECT_EQ(typed.received_ns(), 1'700'000'000'123'456'789u);
  return typed;
}

TEST(ToSample, IAmHereFeedsTheDirectoryNotATopic) {
  EXPECT_FALSE(to_sample(1, codec::IAmHere{0, 1, false}, kReceived));
}

TEST(ToSample, EveryTelemetryMessageInEngineeringUnits) {
  EXPECT_FLOAT_EQ(sample_of<ValvePosition>(codec::Position{123.4}).degrees(), 123.4f);
  const auto temperature = sample_of<ValveTemperature>(codec::Temperature{-5, 40});
  EXPECT_EQ(temperature.valve_c(), -5);
  EXPECT_EQ(temperature.sensor_c(), 40);
  EXPECT_FLOAT_EQ(sample_of<ValveVoltage>(codec::Voltage{12.0}).volts(), 12.0f);
  const auto current = sample_of<ValveCurrent>(codec::RunCurrent{1.5, 2.34});
  EXPECT_FLOAT_EQ(current.amps(), 1.5f);
  EXPECT_FLOAT_EQ(current.last_running_amps(), 2.34f);
  const auto dps =
      sample_of<ValveDegreesPerSecond>(codec::DegreesPerSecond{90, codec::Direction::kOpen});
  EXPECT_EQ(dps.dps(), 90);
  EXPECT_EQ(dps.direction(), DIRECTION_OPEN);
  const auto speed = sample_of<ValveSpeedDirection>(
      codec::SpeedDirection{100, codec::Direction::kClose, codec::Rotation::kCounterclockwise});
  EXPECT_EQ(speed.speed_percent(), 100);
  EXPECT_EQ(speed.direction(), DIRECTION_CLOSE);
  EXPECT_EQ(speed.opening_direction(), ROTATION_COUNTERCLOCKWISE);
  EXPECT_EQ(sample_of<ValveRunTime>(codec::RunTime{3600}).seconds(), 3600u);
  EXPECT_EQ(sample_of<ValveCycleCount>(codec::CycleCounts{70000}).count(), 70000u);
  EXPECT_EQ(sample_of<ValveBaudRate>(codec::BaudRateReply{500000}).bit_rate(), 500000u);
  const auto version = sample_of<ValveVersion>(codec::VersionInfo{{1, 2, 'e'}, {2, 10, 0}});
  EXPECT_EQ(version.application().major(), 1);
  EXPECT_EQ(version.application().minor(), 2);
  EXPECT_EQ(version.application().test(), 'e');
  EXPECT_EQ(version.bootloader().minor(), 10);
}

TEST(ToSample, EachErrorBecomesAValveErrorOfItsKind) {
  struct Case {
    codec::FromValveMessage message;
    ErrorKind kind;
    float value, limit;
  };
  const Case cases[] = {
      {codec::HighVoltageError{17.2, 16.5}, ERROR_HIGH_VOLTAGE, 17.2f, 16.5f},
      {codec::LowVoltageError{8.5, 9.0}, ERROR_LOW_VOLTAGE, 8.5f, 9.0f},
      {codec::HighCurrentError{3.1, 3.0}, ERROR_HIGH_CURRENT, 3.1f, 3.0f},
      {codec::LowCurrentError{0.05, 0.1}, ERROR_LOW_CURRENT, 0.05f, 0.1f},
      {codec::HighTemperatureError{90, 85}, ERROR_HIGH_TEMPERATURE, 90.0f, 85.0f},
      {codec::MinDegreesPerSecondError{12, 20, codec::Direction::kOpen},
       ERROR_MIN_DEGREES_PER_SECOND, 12.0f, 20.0f},
  };
  for (const auto& c : cases) {
    const auto error = sample_of<ValveError>(c.message);
    EXPECT_EQ(error.kind(), c.kind);
    EXPECT_FLOAT_EQ(error.value(), c.value);
    EXPECT_FLOAT_EQ(error.limit(), c.limit);
  }
  EXPECT_EQ(sample_of<ValveError>(codec::MinDegreesPerSecondError{12, 20, codec::Direction::kOpen})
                .direction(),
            DIRECTION_OPEN);
}

ValveCommand command(CommandKind kind) {
  ValveCommand c;
  c.serial(1);
  c.kind(kind);
  c.speed_percent(50);
  c.direction(DIRECTION_OPEN);
  return c;
}

TEST(ToMessage, EveryCommandKind) {
  EXPECT_EQ(*to_message(command(COMMAND_STOP)), codec::ToValveMessage{codec::Stop{}});
  EXPECT_EQ(*to_message(command(COMMAND_CLEAR_ERRORS)),
            codec::ToValveMessage{codec::ClearErrors{}});
  EXPECT_EQ(*to_message(command(COMMAND_MANUAL)),
            (codec::ToValveMessage{codec::Manual{50, codec::Direction::kOpen}}));
  auto target = command(COMMAND_TARGET_DEGREES);
  target.direction(DIRECTION_SHORTEST);
  target.degrees(123.4f);
  const auto target_message = std::get<codec::TargetDegrees>(*to_message(target));
  EXPECT_EQ(target_message.direction, codec::TargetDirection::kShortest);
  EXPECT_NEAR(target_message.degrees, 123.4, 1e-4);
  auto relative = command(COMMAND_DEGREES_FROM_POSITION);
  relative.direction(DIRECTION_CLOSE);
  relative.degrees(45.5f);
  EXPECT_EQ(
      *to_message(relative),
      (codec::ToValveMessage{codec::DegreesFromPosition{50, codec::Direction::kClose, 45.5}}));
  auto timed = command(COMMAND_MILLISECONDS_TO_RUN);
  timed.milliseconds(1500);
  EXPECT_EQ(*to_message(timed),
            (codec::ToValveMessage{codec::MillisecondsToRun{50, codec::Direction::kOpen, 1500}}));
  auto request = command(COMMAND_REQUEST);
  request.telemetry(TELEMETRY_CYCLE_COUNTS);
  request.resend_tenths(50);
  EXPECT_EQ(*to_message(request), codec::ToValveMessage{codec::RequestCycleCounts{50}});
  request.telemetry(TELEMETRY_VERSION);
  request.resend_tenths(0);
  EXPECT_EQ(*to_message(request), codec::ToValveMessage{codec::RequestVersion{}});
  auto baud = command(COMMAND_SET_BAUD_RATE);
  baud.bit_rate(500000);
  EXPECT_EQ(*to_message(baud),
            (codec::ToValveMessage{codec::BaudRate{codec::BaudAction::kSet, 500000}}));
  EXPECT_EQ(*to_message(command(COMMAND_REQUEST_BAUD_RATE)),
            (codec::ToValveMessage{codec::BaudRate{codec::BaudAction::kRequest, 250000}}));
}

TEST(ToMessage, RefusesWhatTheSheetCannotExpress) {
  auto manual = command(COMMAND_MANUAL);
  manual.direction(DIRECTION_SHORTEST);
  EXPECT_EQ(to_message(manual).error().reason,
            "manual: direction SHORTEST exists only for Target Degrees");
  auto version = command(COMMAND_REQUEST);
  version.telemetry(TELEMETRY_VERSION);
  version.resend_tenths(10);
  EXPECT_EQ(to_message(version).error().reason,
            "request: version is sent once; resend_tenths must be 0");
  EXPECT_FALSE(to_message(command(static_cast<CommandKind>(42))));
}

// Clients build commands from protocol messages (valvectl checks its arguments with the codec
// that way): every message a command can carry comes back unchanged.
TEST(ToCommand, IsTheInverseOfToMessage) {
  const std::vector<codec::ToValveMessage> messages{
      codec::Stop{},
      codec::Manual{40, codec::Direction::kClose},
      codec::TargetDegrees{100, codec::TargetDirection::kShortest, 123.5},
      codec::DegreesFromPosition{5, codec::Direction::kOpen, 0.5},
      codec::ClearErrors{},
      codec::MillisecondsToRun{60, codec::Direction::kOpen, 65535},
      codec::RequestVersion{},
      codec::RequestPosition{1},
      codec::RequestTemperature{0},
      codec::RequestVoltage{255},
      codec::RequestCurrent{10},
      codec::RequestDegreesPerSecond{10},
      codec::RequestSpeedDirection{10},
      codec::RequestRunTime{50},
      codec::RequestCycleCounts{50},
      codec::BaudRate{codec::BaudAction::kSet, codec::kBitRate500k},
      codec::BaudRate{codec::BaudAction::kRequest, codec::kBitRate250k}};
  for (const auto& message : messages) {
    const auto back = to_message(to_command(message));
    ASSERT_TRUE(back) << codec::message_name(message) << ": " << back.error().reason;
    EXPECT_EQ(*back, message) << codec::message_name(message);
  }
  EXPECT_EQ(to_command(codec::TargetDegrees{100, codec::TargetDirection::kOpen, 45.0}).kind(),
            COMMAND_TARGET_DEGREES);
}

TEST(Names, AreTheSnakeCaseWordsOfLogsAndJson) {
  EXPECT_EQ(to_string(COMMAND_DEGREES_FROM_POSITION), "degrees_from_position");
  EXPECT_EQ(to_string(COMMAND_REQUEST_BAUD_RATE), "request_baud_rate");
  EXPECT_EQ(to_string(COMMAND_SUPERSEDED), "superseded");
  EXPECT_EQ(to_string(DIRECTION_SHORTEST), "shortest");
  EXPECT_EQ(to_string(ERROR_MIN_DEGREES_PER_SECOND), "min_degrees_per_second");
  EXPECT_EQ(to_string(BUS_ERROR_PASSIVE), "error_passive");
  EXPECT_EQ(to_string(static_cast<CommandKind>(42)), "unknown_command");
}

TEST(DdsDuration, TimeoutsBecomeSecondsAndNanosecondsClampedToWhatFastDdsHolds) {
  using namespace std::chrono_literals;
  const auto one_and_a_half = to_dds_duration(1500ms);
  EXPECT_EQ(one_and_a_half.seconds, 1);
  EXPECT_EQ(one_and_a_half.nanosec, 500'000'000u);
  const auto past = to_dds_duration(-3s);  // a deadline already passed
  EXPECT_EQ(past.seconds, 0);
  EXPECT_EQ(past.nanosec, 0u);
  const auto far = to_dds_duration(std::chrono::hours(24 * 365 * 100));
  EXPECT_EQ(far.seconds, 0x7FFFFFFF);
  EXPECT_EQ(far.nanosec, 0u);
}

}  // namespace
}  // namespace teejet::dds
