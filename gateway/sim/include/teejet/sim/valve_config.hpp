#pragma once

// What one simulated valve is: its identity, its mechanics and the values it reports, and the
// errors a test can make it raise. Plain data; see docs/valve-sim.md.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "teejet/can/bus.hpp"
#include "teejet/codec/table.hpp"
#include "teejet/core/result.hpp"

namespace teejet::sim {

// Opened Degrees of a full-turn ("360-degree") valve, which is also its circle.
inline constexpr double kFullTurnDegrees = codec::kFullTurnOpenedDegrees;
inline constexpr std::uint32_t kMaxSerial = 0xFFFFFF;

struct ValveConfig {
  std::uint32_t serial = 1;       // 24 bits, shown as TJV000001
  std::uint32_t part_number = 0;  // 24 bits; "not used for now" by the sheet
  // Degrees per second at 100 % speed; a speed of S % turns at S % of it. 0 < dps <= 359 (the
  // Degrees Per Second message reports it rounded to a whole degree).
  double degrees_per_second = 90.0;
  double closed_degrees = 0.0;
  double opened_degrees = 90.0;  // 360: full-turn valve; otherwise closed < opened <= 340
  codec::Rotation opening_direction = codec::Rotation::kClockwise;
  std::optional<double> start_degrees;  // position at power-up; default: closed_degrees
  codec::SoftwareVersion application_version{1, 0, 0};
  codec::SoftwareVersion bootloader_version{1, 0, 0};
  double volts = 12.0;                           // 0 .. 16.5
  int valve_temperature_c = 25;                  // -127 .. 127
  int sensor_temperature_c = 25;                 // -127 .. 127
  double running_amps = 0.5;                     // current at 100 % speed; 0 .. 655.35
  std::uint32_t bit_rate = codec::kBitRate250k;  // what baud-rate requests report

  bool full_turn() const { return opened_degrees >= kFullTurnDegrees; }
  double start_position() const { return start_degrees.value_or(closed_degrees); }
};

// OK, or the first thing wrong with the configuration, naming the valve and the field.
Status validate(const ValveConfig& config);

// ---- Error injection --------------------------------------------------------------------------

// An error a valve reports until Clear Errors: one of the codec's error messages
// (codec::error_kinds()) with its values, volts, amps, degrees Celsius or degrees per second.
using InjectedError = codec::FromValveMessage;

// The error of `kind` (codec::error_message's words: high_voltage, ..., min_degrees_per_second;
// also high-voltage and min-dps) with its measured value, its limit and, for the kinds that have
// one, its direction ("open" or "close"); every value checked by the codec.
Result<InjectedError> make_error(std::string_view kind, double value, double limit,
                                 std::optional<std::string_view> direction = std::nullopt);

// OK, or why `error` cannot be latched: it is not an error message, or the codec refuses one of
// its values.
Status validate(const InjectedError& error);

struct SerialError {
  std::uint32_t serial = 0;
  InjectedError error;

  friend bool operator==(const SerialError&, const SerialError&) = default;
};

// Parses the --inject-error syntax SERIAL:KIND:VALUE:LIMIT[:DIRECTION], e.g.
// "TJV000001:high-voltage:16.2:15.5" or "123456:min-dps:20:30:close". The values are checked.
Result<SerialError> parse_error_spec(std::string_view text);

// "clockwise" / "counterclockwise" (also "cw" / "ccw").
std::optional<codec::Rotation> parse_rotation(std::string_view text);

}  // namespace teejet::sim
