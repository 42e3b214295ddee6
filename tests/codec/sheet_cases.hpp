#pragma once

// Every message of the protocol sheet with its bytes worked out by hand (big-endian, scaled as
// the sheet says). Shared by the wire-format, error-path and robustness tests.

#include <gtest/gtest.h>

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "teejet/codec/codec.hpp"

namespace teejet::codec::testing {

struct SheetCase {
  std::string name;  // the message's public name, as valve-decode prints it
  AnyMessage message;
  std::vector<std::uint8_t> bytes;  // exactly the sheet's length, id byte first
  std::vector<std::string> field_names;
};

inline AnyMessage to_valve(ToValveMessage m) { return AnyMessage{std::in_place_index<0>, m}; }
inline AnyMessage from_valve(FromValveMessage m) { return AnyMessage{std::in_place_index<1>, m}; }

inline std::vector<SheetCase> sheet_cases() {
  using D = Direction;
  using TD = TargetDirection;
  const std::vector<std::string> drive{"speed_percent", "direction"};
  const std::vector<std::string> move{"speed_percent", "direction", "degrees"};
  const std::vector<std::string> resend{"resend_tenths"};
  return {
      // ---- controller to valve
      {"stop", to_valve(Stop{}), {0x00}, {}},
      {"manual", to_valve(Manual{50, D::kOpen}), {0x01, 0x32, 0x01}, drive},
      {"target_degrees",
       to_valve(TargetDegrees{75, TD::kOpen, 123.4}),
       {0x02, 0x4B, 0x01, 0x04, 0xD2},
       move},
      {"target_degrees",
       to_valve(TargetDegrees{100, TD::kShortest, 359.9}),
       {0x02, 0x64, 0x02, 0x0E, 0x0F},
       move},
      {"degrees_from_position",
       to_valve(DegreesFromPosition{30, D::kClose, 45.5}),
       {0x03, 0x1E, 0x00, 0x01, 0xC7},
       move},
      {"clear_errors", to_valve(ClearErrors{}), {0x04}, {}},
      {"milliseconds_to_run",
       to_valve(MillisecondsToRun{100, D::kOpen, 1500}),
       {0x05, 0x64, 0x01, 0x05, 0xDC},
       {"speed_percent", "direction", "milliseconds"}},
      {"request_version", to_valve(RequestVersion{}), {0x10}, {}},
      {"request_position", to_valve(RequestPosition{1}), {0x11, 0x01}, resend},
      {"request_temperature", to_valve(RequestTemperature{10}), {0x12, 0x0A}, resend},
      {"request_voltage", to_valve(RequestVoltage{10}), {0x13, 0x0A}, resend},
      {"request_current", to_valve(RequestCurrent{20}), {0x14, 0x14}, resend},
      {"request_degrees_per_second", to_valve(RequestDegreesPerSecond{0}), {0x15, 0x00}, resend},
      {"request_speed_direction", to_valve(RequestSpeedDirection{5}), {0x16, 0x05}, resend},
      {"request_run_time", to_valve(RequestRunTime{50}), {0x17, 0x32}, resend},
      {"request_cycle_counts", to_valve(RequestCycleCounts{255}), {0x18, 0xFF}, resend},
      {"baud_rate",
       to_valve(BaudRate{BaudAction::kSet, 500000}),
       {0x93, 0xA5, 0x01},
       {"action", "bit_rate"}},
      {"baud_rate",
       to_valve(BaudRate{BaudAction::kRequest, 250000}),
       {0x93, 0x55, 0x00},
       {"action", "bit_rate"}},
      // ---- valve to controller
      {"i_am_here",
       from_valve(IAmHere{0x012345, 123456, false}),
       {0x00, 0x01, 0x23, 0x45, 0x01, 0xE2, 0x40, 0x00},
       {"part_number", "serial", "boot_mode"}},
      {"i_am_here",
       from_valve(IAmHere{0, 999999, true}),
       {0x00, 0x00, 0x00, 0x00, 0x0F, 0x42, 0x3F, 0x01},
       {"part_number", "serial", "boot_mode"}},
      {"version",
       from_valve(VersionInfo{{1, 2, 'e'}, {2, 10, 0}}),
       {0x01, 0x01, 0x02, 0x65, 0x02, 0x0A, 0x00},
       {"application", "bootloader"}},
      {"position", from_valve(Position{123.4}), {0x02, 0x04, 0xD2}, {"degrees"}},
      {"position", from_valve(Position{90.0}), {0x02, 0x03, 0x84}, {"degrees"}},
      {"temperature", from_valve(Temperature{-5, 40}), {0x03, 0xFB, 0x28}, {"valve_c", "sensor_c"}},
      {"temperature",
       from_valve(Temperature{-127, 127}),
       {0x03, 0x81, 0x7F},
       {"valve_c", "sensor_c"}},
      {"voltage", from_valve(Voltage{12.0}), {0x04, 0x00, 0x78}, {"volts"}},
      {"voltage", from_valve(Voltage{16.5}), {0x04, 0x00, 0xA5}, {"volts"}},
      {"run_current",
       from_valve(RunCurrent{1.5, 2.34}),
       {0x05, 0x00, 0x96, 0x00, 0xEA},
       {"amps", "last_running_amps"}},
      {"degrees_per_second",
       from_valve(DegreesPerSecond{90, D::kOpen}),
       {0x06, 0x00, 0x5A, 0x01},
       {"dps", "direction"}},
      {"speed_direction",
       from_valve(SpeedDirection{100, D::kClose, Rotation::kClockwise}),
       {0x07, 0x64, 0x00, 0x01},
       {"speed_percent", "direction", "opening_direction"}},
      {"speed_direction",
       from_valve(SpeedDirection{0, D::kOpen, Rotation::kCounterclockwise}),
       {0x07, 0x00, 0x01, 0x00},
       {"speed_percent", "direction", "opening_direction"}},
      {"run_time", from_valve(RunTime{3600}), {0x08, 0x00, 0x00, 0x0E, 0x10}, {"seconds"}},
      {"run_time", from_valve(RunTime{4294967295u}), {0x08, 0xFF, 0xFF, 0xFF, 0xFF}, {"seconds"}},
      {"cycle_counts", from_valve(CycleCounts{70000}), {0x09, 0x00, 0x01, 0x11, 0x70}, {"count"}},
      {"high_voltage_error",
       from_valve(HighVoltageError{17.2, 16.5}),
       {0x10, 0x00, 0xAC, 0x00, 0xA5},
       {"volts", "limit_volts"}},
      {"low_voltage_error",
       from_valve(LowVoltageError{8.5, 9.0}),
       {0x11, 0x00, 0x55, 0x00, 0x5A},
       {"volts", "limit_volts"}},
      {"high_current_error",
       from_valve(HighCurrentError{3.1, 3.0}),
       {0x12, 0x01, 0x36, 0x01, 0x2C},
       {"amps", "limit_amps"}},
      {"low_current_error",
       from_valve(LowCurrentError{0.05, 0.1}),
       {0x13, 0x00, 0x05, 0x00, 0x0A},
       {"amps", "limit_amps"}},
      {"high_temperature_error",
       from_valve(HighTemperatureError{90, 85}),
       {0x14, 0x5A, 0x55},
       {"temperature_c", "limit_c"}},
      {"min_degrees_per_second_error",
       from_valve(MinDegreesPerSecondError{12, 20, D::kClose}),
       {0x15, 0x00, 0x0C, 0x00, 0x14, 0x00},
       {"dps", "limit_dps", "direction"}},
      {"baud_rate_reply", from_valve(BaudRateReply{500000}), {0x93, 0xA5, 0x01}, {"bit_rate"}},
      {"baud_rate_reply", from_valve(BaudRateReply{250000}), {0x93, 0xA5, 0x00}, {"bit_rate"}},
  };
}

// Messages with at least one field byte after the id: the ones that can be truncated.
inline std::vector<SheetCase> sheet_cases_with_fields() {
  std::vector<SheetCase> out;
  for (auto& c : sheet_cases()) {
    if (c.bytes.size() > 1) out.push_back(std::move(c));
  }
  return out;
}

// Failure messages show the case as "position 02 04 D2", not as raw object bytes.
inline void PrintTo(const SheetCase& c, std::ostream* out) {
  *out << c.name;
  for (auto b : c.bytes) *out << ' ' << std::hex << std::uppercase << int{b};
}

// gtest parameter names: the message name plus its index, e.g. "position_21".
inline std::string case_name(const ::testing::TestParamInfo<SheetCase>& info) {
  return info.param.name + "_" + std::to_string(info.index);
}

inline bool is_to_valve(const SheetCase& c) { return c.message.index() == 0; }

// Encodes a case for valve address 0xD8 through the public API.
inline Result<CanFrame> encode_case(const SheetCase& c, const EncodeOptions& options = {}) {
  if (is_to_valve(c)) return encode(0xD8, std::get<0>(c.message), options);
  return encode(0xD8, std::get<1>(c.message), options);
}

inline CanFrame frame_of(const SheetCase& c, std::vector<std::uint8_t> bytes) {
  CanFrame frame;
  frame.id = is_to_valve(c) ? 0x18EFD8D5 : 0x18EFD5D8;
  frame.dlc = static_cast<std::uint8_t>(bytes.size());
  for (std::size_t i = 0; i < bytes.size(); ++i) frame.data[i] = bytes[i];
  return frame;
}

}  // namespace teejet::codec::testing
