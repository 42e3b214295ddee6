#pragma once

// Typed messages of the TeeJet CAN valve protocol, in engineering units. Integer members are
// wider than their wire fields on purpose: the encoder range-checks them and refuses what the
// sheet does not allow instead of truncating silently.

#include <cstdint>
#include <variant>

namespace teejet::codec {

// Semantic drive direction; the wire values are the sheet's (Open = 1, Close = 0).
enum class Direction : std::uint8_t { kClose = 0, kOpen = 1 };

// Target Degrees direction. kShortest = 2 is this project's choice: the sheet names shortest
// path for 360-degree valves but defines only 0 and 1 (see docs/protocol.md).
enum class TargetDirection : std::uint8_t { kClose = 0, kOpen = 1, kShortest = 2 };

// Opening direction looking at the top of the valve.
enum class Rotation : std::uint8_t { kCounterclockwise = 0, kClockwise = 1 };

// Marker byte of Set or Request CAN Baud Rate.
enum class BaudAction : std::uint8_t { kSet = 0xA5, kRequest = 0x55 };

inline constexpr std::uint32_t kBitRate250k = 250000;
inline constexpr std::uint32_t kBitRate500k = 500000;

// ---- Controller to valve -------------------------------------------------------------------

struct Stop {
  friend bool operator==(const Stop&, const Stop&) = default;
};

struct Manual {
  unsigned speed_percent = 0;  // 0 (stop) .. 100
  Direction direction = Direction::kClose;
  friend bool operator==(const Manual&, const Manual&) = default;
};

struct TargetDegrees {
  unsigned speed_percent = 0;
  TargetDirection direction = TargetDirection::kClose;
  double degrees = 0.0;  // 0.0 .. 359.9, sent in tenths
  friend bool operator==(const TargetDegrees&, const TargetDegrees&) = default;
};

struct DegreesFromPosition {
  unsigned speed_percent = 0;
  Direction direction = Direction::kClose;
  double degrees = 0.0;  // 0.0 .. 359.9, sent in tenths
  friend bool operator==(const DegreesFromPosition&, const DegreesFromPosition&) = default;
};

struct ClearErrors {
  friend bool operator==(const ClearErrors&, const ClearErrors&) = default;
};

struct MillisecondsToRun {
  unsigned speed_percent = 0;
  Direction direction = Direction::kClose;
  unsigned milliseconds = 0;  // 0 .. 65535
  friend bool operator==(const MillisecondsToRun&, const MillisecondsToRun&) = default;
};

struct RequestVersion {
  friend bool operator==(const RequestVersion&, const RequestVersion&) = default;
};

// The eight "request with automatic resend" messages share one shape; the id tells them apart.
template <std::uint8_t MessageId>
struct TelemetryRequest {
  static constexpr std::uint8_t kId = MessageId;
  unsigned resend_tenths = 0;  // resend every N tenths of a second; 0 = send once
  friend bool operator==(const TelemetryRequest&, const TelemetryRequest&) = default;
};

using RequestPosition = TelemetryRequest<0x11>;
using RequestTemperature = TelemetryRequest<0x12>;
using RequestVoltage = TelemetryRequest<0x13>;
using RequestCurrent = TelemetryRequest<0x14>;
using RequestDegreesPerSecond = TelemetryRequest<0x15>;
using RequestSpeedDirection = TelemetryRequest<0x16>;
using RequestRunTime = TelemetryRequest<0x17>;
using RequestCycleCounts = TelemetryRequest<0x18>;

struct BaudRate {
  BaudAction action = BaudAction::kRequest;
  std::uint32_t bit_rate = kBitRate250k;  // 250000 or 500000; a request carries it too
  friend bool operator==(const BaudRate&, const BaudRate&) = default;
};

using ToValveMessage =
    std::variant<Stop, Manual, TargetDegrees, DegreesFromPosition, ClearErrors, MillisecondsToRun,
                 RequestVersion, RequestPosition, RequestTemperature, RequestVoltage,
                 RequestCurrent, RequestDegreesPerSecond, RequestSpeedDirection, RequestRunTime,
                 RequestCycleCounts, BaudRate>;

// ---- Valve to controller -------------------------------------------------------------------

struct IAmHere {
  std::uint32_t part_number = 0;  // 24 bits
  std::uint32_t serial = 0;       // 24 bits, shown as TJV + six digits
  bool boot_mode = false;         // true: running boot code, false: application
  friend bool operator==(const IAmHere&, const IAmHere&) = default;
};

struct SoftwareVersion {
  unsigned major = 0;  // 0 .. 255
  unsigned minor = 0;  // 0 .. 255
  char test = 0;       // test character, 0 for a released version
  friend bool operator==(const SoftwareVersion&, const SoftwareVersion&) = default;
};

struct VersionInfo {
  SoftwareVersion application;
  SoftwareVersion bootloader;
  friend bool operator==(const VersionInfo&, const VersionInfo&) = default;
};

struct Position {
  double degrees = 0.0;  // 0.0 .. 359.9
  friend bool operator==(const Position&, const Position&) = default;
};

struct Temperature {
  int valve_c = 0;   // -127 .. 127
  int sensor_c = 0;  // -127 .. 127
  friend bool operator==(const Temperature&, const Temperature&) = default;
};

struct Voltage {
  double volts = 0.0;  // 0.0 .. 16.5
  friend bool operator==(const Voltage&, const Voltage&) = default;
};

struct RunCurrent {
  double amps = 0.0;               // 0.00 .. 655.35
  double last_running_amps = 0.0;  // 0.00 .. 655.35
  friend bool operator==(const RunCurrent&, const RunCurrent&) = default;
};

struct DegreesPerSecond {
  unsigned dps = 0;  // 0 .. 359
  Direction direction = Direction::kClose;
  friend bool operator==(const DegreesPerSecond&, const DegreesPerSecond&) = default;
};

struct SpeedDirection {
  unsigned speed_percent = 0;  // 0 .. 100
  Direction direction = Direction::kClose;
  Rotation opening_direction = Rotation::kClockwise;
  friend bool operator==(const SpeedDirection&, const SpeedDirection&) = default;
};

struct RunTime {
  std::uint32_t seconds = 0;
  friend bool operator==(const RunTime&, const RunTime&) = default;
};

struct CycleCounts {
  std::uint32_t count = 0;
  friend bool operator==(const CycleCounts&, const CycleCounts&) = default;
};

template <std::uint8_t MessageId>
struct VoltageError {
  static constexpr std::uint8_t kId = MessageId;
  double volts = 0.0;        // 0.0 .. 6553.5
  double limit_volts = 0.0;  // 0.0 .. 6553.5
  friend bool operator==(const VoltageError&, const VoltageError&) = default;
};
using HighVoltageError = VoltageError<0x10>;
using LowVoltageError = VoltageError<0x11>;

template <std::uint8_t MessageId>
struct CurrentError {
  static constexpr std::uint8_t kId = MessageId;
  double amps = 0.0;        // 0.00 .. 655.35
  double limit_amps = 0.0;  // 0.00 .. 655.35
  friend bool operator==(const CurrentError&, const CurrentError&) = default;
};
using HighCurrentError = CurrentError<0x12>;
using LowCurrentError = CurrentError<0x13>;

struct HighTemperatureError {
  int temperature_c = 0;  // 0 .. 127
  int limit_c = 0;        // 0 .. 127
  friend bool operator==(const HighTemperatureError&, const HighTemperatureError&) = default;
};

struct MinDegreesPerSecondError {
  unsigned dps = 0;        // 0 .. 359
  unsigned limit_dps = 0;  // 0 .. 359
  Direction direction = Direction::kClose;
  friend bool operator==(const MinDegreesPerSecondError&,
                         const MinDegreesPerSecondError&) = default;
};

struct BaudRateReply {
  std::uint32_t bit_rate = kBitRate250k;  // 250000 or 500000
  friend bool operator==(const BaudRateReply&, const BaudRateReply&) = default;
};

using FromValveMessage =
    std::variant<IAmHere, VersionInfo, Position, Temperature, Voltage, RunCurrent, DegreesPerSecond,
                 SpeedDirection, RunTime, CycleCounts, HighVoltageError, LowVoltageError,
                 HighCurrentError, LowCurrentError, HighTemperatureError, MinDegreesPerSecondError,
                 BaudRateReply>;

}  // namespace teejet::codec
