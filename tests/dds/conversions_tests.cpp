#include <gtest/gtest.h>

#include <cstdio>
#include <nlohmann/json.hpp>

#include "support/valve_commands.hpp"
#include "teejet/codec/table.hpp"
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
  EXPECT_EQ(sample_of<ValveCycleCounts>(codec::CycleCounts{70000}).count(), 70000u);
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

// Every reply of the codec's table becomes a sample: a new reply without its to_sample overload
// would be dropped on the floor.
TEST(ToSample, EveryReplyOfTheTableHasASample) {
  for (const auto& message : codec::message_table(codec::Flow::kFromValve)) {
    if (message.subject.empty() && message.error_kind.empty()) continue;  // I'm Here
    const auto blank = *codec::from_valve_message(message.id);
    const auto sample = to_sample(1, blank, kReceived);
    ASSERT_TRUE(sample) << message.name;
    EXPECT_EQ(codec::message_id(from_sample(*sample)), message.id) << message.name;
  }
}

TEST(FromSample, IsTheInverseOfToSample) {
  const std::vector<codec::FromValveMessage> messages{
      codec::VersionInfo{{1, 2, 'e'}, {2, 10, 0}},
      codec::Position{123.4},
      codec::Temperature{-5, 40},
      codec::Voltage{12.1},
      codec::RunCurrent{1.5, 2.34},
      codec::DegreesPerSecond{90, codec::Direction::kOpen},
      codec::SpeedDirection{100, codec::Direction::kClose, codec::Rotation::kCounterclockwise},
      codec::RunTime{3600},
      codec::CycleCounts{70000},
      codec::BaudRateReply{500000},
      codec::HighVoltageError{17.2, 16.5},
      codec::LowVoltageError{8.5, 9.0},
      codec::HighCurrentError{3.1, 3.0},
      codec::LowCurrentError{0.05, 0.1},
      codec::HighTemperatureError{90, 85},
      codec::MinDegreesPerSecondError{12, 20, codec::Direction::kOpen}};
  for (const auto& message : messages) {
    EXPECT_EQ(from_sample(*to_sample(1, message, kReceived)), message)
        << codec::message_name(message);
  }
}

// --json printed 74.60000000000001 for the 74.6 a valve sent. Every value of the wire's grid,
// as the float DDS carries it, comes back as the decimal the valve sent.
TEST(FromSample, EveryPositionOfTheSheetIsTheDecimalTheValveSent) {
  int wrong = 0;
  for (int tenths = 0; tenths <= 3599; ++tenths) {
    char expected[16];
    std::snprintf(expected, sizeof expected, "%d.%d", tenths / 10, tenths % 10);
    ValvePosition sample;
    sample.degrees(static_cast<float>(tenths) / 10.0f);
    const double degrees = std::get<codec::Position>(from_sample(sample)).degrees;
    const std::string printed = nlohmann::json(degrees).dump();
    if (printed != expected) {
      ++wrong;
      ADD_FAILURE() << "sent " << expected << ", printed " << printed;
    }
  }
  EXPECT_EQ(wrong, 0);
}

TEST(FromSample, HundredthsAreTheDecimalsTheValveSent) {
  for (const auto& [sent, expected] : std::vector<std::pair<float, std::string>>{
           {0.35f, "0.35"}, {1.07f, "1.07"}, {12.29f, "12.29"}, {655.35f, "655.35"}}) {
    ValveCurrent sample;
    sample.amps(sent);
    EXPECT_EQ(nlohmann::json(std::get<codec::RunCurrent>(from_sample(sample)).amps).dump(),
              expected);
  }
}

// Valve 1, opening at half speed: a speed that is lost or defaulted shows in the messages.
ValveCommand command(CommandKind kind) { return testing::command(1, kind, 50); }

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
            "manual: direction \"shortest\" is not one of close, open");
  EXPECT_EQ(to_message(manual).error().field, "direction");
  auto version = command(COMMAND_REQUEST);
  version.telemetry(TELEMETRY_VERSION);
  version.resend_tenths(10);
  EXPECT_EQ(to_message(version).error().reason,
            "version: resend_tenths 10 is not 0: the valve sends it once");
  auto fast = command(COMMAND_MANUAL);
  fast.speed_percent(101);
  EXPECT_EQ(to_message(fast).error().reason, "manual: speed_percent 101 is outside 0 to 100");
  auto undefined = command(COMMAND_REQUEST);
  undefined.telemetry(static_cast<Telemetry>(42));
  EXPECT_EQ(to_message(undefined).error().reason, "request: telemetry 42 is undefined");
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
  EXPECT_EQ(to_string(TELEMETRY_CYCLE_COUNTS), "cycle_counts");
  EXPECT_EQ(to_string(TELEMETRY_CURRENT), "current");
  EXPECT_EQ(to_string(static_cast<Direction>(7)), "unknown");
  EXPECT_EQ(telemetry_of("run-time"), TELEMETRY_RUN_TIME);
  EXPECT_EQ(telemetry_of("dps"), TELEMETRY_DEGREES_PER_SECOND);
  EXPECT_EQ(telemetry_of("baud_rate"), std::nullopt);
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

TEST(DdsTime, UnixNanosecondsBecomeTheSourceTimestampOfAWrite) {
  const auto stamp = to_dds_time(1'764'158'400'123'456'789);  // 2025-11-26 12:00:00.123456789
  EXPECT_EQ(stamp.seconds, 1'764'158'400);
  EXPECT_EQ(stamp.nanosec, 123'456'789u);
  EXPECT_EQ(stamp.to_ns(), 1'764'158'400'123'456'789);
  EXPECT_EQ(to_dds_time(0).to_ns(), 0);
  EXPECT_EQ(to_dds_time(~std::uint64_t{0}).seconds, 0x7FFFFFFF);  // past 2038: the largest
}

}  // namespace
}  // namespace teejet::dds
