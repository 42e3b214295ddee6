// The message table as data: what tools outside the codec read instead of restating the sheet.

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "teejet/codec/table.hpp"

namespace teejet::codec {
namespace {

const FieldInfo& field_of(const MessageInfo& message, std::string_view name) {
  const FieldInfo* field = find_field(message, name);
  if (field == nullptr) {
    ADD_FAILURE() << message.name << " has no field " << name;
    static const FieldInfo kNone;
    return kNone;
  }
  return *field;
}

TEST(MessageTable, RangesUnitsAndResolutionsAreTheSheets) {
  const auto& degrees = field_of(describe(TargetDegrees{}), "degrees");
  EXPECT_EQ(degrees.unit, "°");
  EXPECT_EQ(degrees.min, 0.0);
  EXPECT_EQ(degrees.max, 359.9);
  EXPECT_EQ(degrees.resolution, 0.1);
  EXPECT_EQ(degrees.offset, 3u);
  EXPECT_EQ(degrees.width, 2u);

  const auto& speed = field_of(describe(Manual{}), "speed_percent");
  EXPECT_EQ(speed.unit, "%");
  EXPECT_EQ(speed.max, 100.0);
  EXPECT_EQ(speed.resolution, 1.0);

  EXPECT_EQ(field_of(describe(MillisecondsToRun{}), "milliseconds").max, 65535.0);
  EXPECT_EQ(field_of(describe(RequestPosition{}), "resend_tenths").max, 255.0);
  EXPECT_EQ(field_of(describe(Voltage{}), "volts").max, 16.5);
  EXPECT_EQ(field_of(describe(Voltage{}), "volts").unit, "V");
  EXPECT_EQ(field_of(describe(HighVoltageError{}), "volts").max, 6553.5);
  EXPECT_EQ(field_of(describe(RunCurrent{}), "amps").max, 655.35);
  EXPECT_EQ(field_of(describe(RunCurrent{}), "amps").resolution, 0.01);
  EXPECT_EQ(field_of(describe(Temperature{}), "valve_c").min, -127.0);
  EXPECT_EQ(field_of(describe(HighTemperatureError{}), "temperature_c").min, 0.0);
  EXPECT_EQ(field_of(describe(DegreesPerSecond{}), "dps").max, 359.0);
  EXPECT_EQ(field_of(describe(RunTime{}), "seconds").unit, "s");
  EXPECT_EQ(field_of(describe(BaudRate{}), "bit_rate").values,
            (std::vector<double>{250000, 500000}));
  EXPECT_EQ(field_of(describe(TargetDegrees{}), "direction").words,
            (std::vector<std::string_view>{"close", "open", "shortest"}));
  EXPECT_EQ(field_of(describe(Manual{}), "direction").words,
            (std::vector<std::string_view>{"close", "open"}));
  EXPECT_EQ(field_of(describe(BaudRateReply{}), "marker").type, FieldType::kMarker);
}

TEST(MessageTable, EveryMessageOnceInTheSheetsOrder) {
  const auto& to_valve = message_table(Flow::kToValve);
  const auto& from_valve = message_table(Flow::kFromValve);
  ASSERT_EQ(to_valve.size(), 16u);
  ASSERT_EQ(from_valve.size(), 17u);
  EXPECT_EQ(to_valve.front().name, "stop");
  EXPECT_EQ(to_valve.back().id, 0x93);
  EXPECT_EQ(from_valve.front().name, "i_am_here");
  EXPECT_EQ(from_valve[5].name, "run_current");
  for (const auto* table : {&to_valve, &from_valve}) {
    std::set<std::uint8_t> ids;
    for (const MessageInfo& message : *table) {
      EXPECT_TRUE(ids.insert(message.id).second) << message.name;
      for (const FieldInfo& field : message.fields) {
        EXPECT_GE(field.offset, 1u) << message.name << "." << field.name;
        EXPECT_LE(field.offset + field.width, 8u) << message.name << "." << field.name;
        EXPECT_LE(field.min, field.max) << message.name << "." << field.name;
      }
    }
  }
  EXPECT_EQ(&describe(ToValveMessage{RequestCurrent{}}), &to_valve[10]);
  EXPECT_EQ(&describe(FromValveMessage{CycleCounts{}}), &from_valve[9]);
}

TEST(MessageTable, ARequestAndItsReplyShareOneSubject) {
  EXPECT_EQ(subject(RequestCurrent{}), "current");
  EXPECT_EQ(subject(RunCurrent{}), "current");
  EXPECT_EQ(subject(RequestCycleCounts{}), "cycle_counts");
  EXPECT_EQ(subject(CycleCounts{}), "cycle_counts");
  EXPECT_EQ(subject(RequestVersion{}), "version");
  EXPECT_EQ(subject(VersionInfo{}), "version");
  EXPECT_EQ(subject(BaudRate{}), "baud_rate");
  EXPECT_EQ(subject(BaudRateReply{}), "baud_rate");
  EXPECT_EQ(subject(Stop{}), "");
  EXPECT_EQ(subject(IAmHere{}), "");
  EXPECT_EQ(subject(HighVoltageError{}), "");
  EXPECT_EQ(describe(RequestCurrent{}).reply, std::optional<std::uint8_t>{0x05});
  EXPECT_TRUE(describe(Stop{}).run_command);
  EXPECT_FALSE(describe(RequestVersion{}).run_command);
}

TEST(Telemetry, NamesAreTheSubjectsOfTheTelemetryRequests) {
  EXPECT_EQ(telemetry_names(),
            (std::vector<std::string_view>{"version", "position", "temperature", "voltage",
                                           "current", "degrees_per_second", "speed_direction",
                                           "run_time", "cycle_counts"}));
  EXPECT_EQ(telemetry_request("position"), ToValveMessage{RequestPosition{}});
  EXPECT_EQ(telemetry_request("version"), ToValveMessage{RequestVersion{}});
  EXPECT_EQ(telemetry_request("cycle_counts"), ToValveMessage{RequestCycleCounts{}});
  // As people type them: dashes, upper case, and valvectl's older words.
  EXPECT_EQ(telemetry_request("run-time"), ToValveMessage{RequestRunTime{}});
  EXPECT_EQ(telemetry_request("Cycle-Counts"), ToValveMessage{RequestCycleCounts{}});
  EXPECT_EQ(telemetry_request("dps"), ToValveMessage{RequestDegreesPerSecond{}});
  EXPECT_EQ(telemetry_request("speed"), ToValveMessage{RequestSpeedDirection{}});
  // The baud rate is a setting with a command of its own, not telemetry.
  EXPECT_EQ(telemetry_request("baud_rate"), std::nullopt);
  EXPECT_EQ(telemetry_request("request_position"), std::nullopt);
  EXPECT_EQ(telemetry_request(""), std::nullopt);
}

TEST(ErrorKinds, NamesAreTheErrorMessagesWithoutError) {
  EXPECT_EQ(error_kinds(), (std::vector<std::string_view>{
                               "high_voltage", "low_voltage", "high_current", "low_current",
                               "high_temperature", "min_degrees_per_second"}));
  EXPECT_EQ(error_message("high_voltage"), FromValveMessage{HighVoltageError{}});
  EXPECT_EQ(error_message("high-temperature"), FromValveMessage{HighTemperatureError{}});
  EXPECT_EQ(error_message("min-dps"), FromValveMessage{MinDegreesPerSecondError{}});
  EXPECT_EQ(error_message("position"), std::nullopt);
  EXPECT_EQ(error_kind(LowCurrentError{}), "low_current");
  EXPECT_EQ(error_kind(Position{}), "");
}

TEST(SetField, NumbersWordsAndTextAsPeopleGiveThem) {
  ToValveMessage move = TargetDegrees{};
  ASSERT_TRUE(set_field(move, "degrees", 45.3));
  ASSERT_TRUE(set_field(move, "speed_percent", std::int64_t{80}));
  ASSERT_TRUE(set_field(move, "direction", std::string("shortest")));
  EXPECT_EQ(move, ToValveMessage{(TargetDegrees{80, TargetDirection::kShortest, 45.3})});
  EXPECT_EQ(field_value(move, "direction"), FieldValue{std::string("shortest")});

  FromValveMessage here = IAmHere{};
  ASSERT_TRUE(set_field(here, "serial", std::string("TJV000042")));
  ASSERT_TRUE(set_field(here, "boot_mode", true));
  EXPECT_EQ(here, FromValveMessage{(IAmHere{0, 42, true})});

  FromValveMessage version = VersionInfo{};
  ASSERT_TRUE(set_field(version, "application", std::string("1.02e")));
  EXPECT_EQ(std::get<VersionInfo>(version).application, (SoftwareVersion{1, 2, 'e'}));

  ToValveMessage baud = BaudRate{};
  ASSERT_TRUE(set_field(baud, "bit_rate", std::int64_t{500000}));
  EXPECT_EQ(std::get<BaudRate>(baud).bit_rate, kBitRate500k);
}

TEST(SetField, RefusesWhatEncodeRefusesNamingTheField) {
  ToValveMessage manual = Manual{};
  const auto too_fast = set_field(manual, "speed_percent", std::int64_t{101});
  ASSERT_FALSE(too_fast);
  EXPECT_EQ(too_fast.error().code, ErrorCode::kOutOfRange);
  EXPECT_EQ(too_fast.error().field, "speed_percent");
  EXPECT_EQ(too_fast.error().complaint, "101 is outside 0 to 100");
  EXPECT_EQ(too_fast.error().reason, "manual: speed_percent 101 is outside 0 to 100");

  const auto half = set_field(manual, "speed_percent", 50.5);
  ASSERT_FALSE(half);
  EXPECT_EQ(half.error().complaint, "50.5 is not a whole number");

  const auto shortest = set_field(manual, "direction", std::string("shortest"));
  ASSERT_FALSE(shortest);
  EXPECT_EQ(shortest.error().complaint, "\"shortest\" is not one of close, open");

  ToValveMessage move = TargetDegrees{};
  const auto full_circle = set_field(move, "degrees", 360.0);
  ASSERT_FALSE(full_circle);
  EXPECT_EQ(full_circle.error().reason, "target_degrees: degrees 360 is outside 0 to 359.9");

  ToValveMessage baud = BaudRate{};
  EXPECT_EQ(set_field(baud, "bit_rate", std::int64_t{125000}).error().complaint,
            "125000 is neither 250000 nor 500000");
  EXPECT_EQ(set_field(baud, "nonsense", std::int64_t{1}).error().reason,
            "baud_rate has no field nonsense");
  EXPECT_EQ(manual, ToValveMessage{Manual{}}) << "a refused value must change nothing";
}

TEST(ValveLimits, OpenedAtMost340OrAFullTurn) {
  EXPECT_TRUE(check_valve_limits(0, 90));
  EXPECT_TRUE(check_valve_limits(10, 340));
  EXPECT_TRUE(check_valve_limits(0, 360));
  EXPECT_TRUE(check_valve_limits(359.9, 360));
  const auto between = check_valve_limits(0, 350);
  ASSERT_FALSE(between);
  EXPECT_EQ(between.error().reason,
            "opened_degrees 350 is neither 360 (full turn) nor at most 340 (the sheet)");
  EXPECT_EQ(check_valve_limits(90, 90).error().reason,
            "closed_degrees 90 must be at least 0 and below opened_degrees 90");
  EXPECT_EQ(check_valve_limits(-1, 90).error().field, "closed_degrees");
  EXPECT_EQ(check_valve_limits(360, 360).error().reason, "closed_degrees 360 is outside [0, 360)");
  EXPECT_FALSE(check_valve_limits(0, std::nan("")));
}

}  // namespace
}  // namespace teejet::codec
