#pragma once

// The protocol sheet as data: one entry per message, with the sheet's offsets (byte 0 is the
// message id), ranges, units and resolutions, which reply answers which request, and which
// messages are run commands, telemetry requests and errors. Ranges are the sheet's;
// docs/protocol.md records where the sheet is silent. Everything else reads these facts through
// teejet/codec/table.hpp; a message added here (and to the variants of messages.hpp) is known
// to every tool by its name.

#include "wire.hpp"

namespace teejet::codec::detail {

// ---- Field kinds with the sheet's ranges ----------------------------------------------------

inline constexpr UnsignedField kSpeedPercent{1, 100, "%"};
inline constexpr UnsignedField kResendTenths{1, 0xFF, "0.1 s"};
inline constexpr UnsignedField kMilliseconds{2, 0xFFFF, "ms"};
inline constexpr UnsignedField kPartNumber{3, 0xFFFFFF};
inline constexpr UnsignedField kSeconds32{4, 0xFFFFFFFF, "s"};
inline constexpr UnsignedField kCount32{4, 0xFFFFFFFF};
inline constexpr UnsignedField kDegreesPerSecond{2, 359, "°/s"};
inline constexpr ScaledField kTenthsOfDegree{2, 10.0, 3599, "°"};  // 0.0 .. 359.9
inline constexpr ScaledField kSupplyVolts{2, 10.0, 165, "V"};      // 0.0 .. 16.5
inline constexpr ScaledField kErrorVolts{2, 10.0, 0xFFFF, "V"};    // errors may exceed the supply
inline constexpr ScaledField kAmps{2, 100.0, 0xFFFF, "A"};         // 0.00 .. 655.35
inline constexpr SignedByteField kCelsius{-127, 127, "°C"};
inline constexpr SignedByteField kErrorCelsius{0, 127, "°C"};
inline constexpr SerialField kSerial{};
inline constexpr FlagField kBootMode{};
inline constexpr VersionField kVersion{};
inline constexpr BitRateField kBitRate{};
inline constexpr EnumField<Direction> kDirection{};
inline constexpr EnumField<TargetDirection> kTargetDirection{};
inline constexpr EnumField<Rotation> kRotation{};
inline constexpr EnumField<BaudAction> kBaudAction{ErrorCode::kInvalidMarker};

// ---- Valve to controller (0x18EFD5<valve>) --------------------------------------------------

constexpr auto spec(std::type_identity<IAmHere>) {
  return message<IAmHere>(0x00, "i_am_here",
                          field("part_number", 1, &IAmHere::part_number, kPartNumber),
                          field("serial", 4, &IAmHere::serial, kSerial),
                          field("boot_mode", 7, &IAmHere::boot_mode, kBootMode));
}

constexpr auto spec(std::type_identity<VersionInfo>) {
  return message<VersionInfo>(0x01, "version",
                              field("application", 1, &VersionInfo::application, kVersion),
                              field("bootloader", 4, &VersionInfo::bootloader, kVersion));
}

constexpr auto spec(std::type_identity<Position>) {
  return message<Position>(0x02, "position",
                           field("degrees", 1, &Position::degrees, kTenthsOfDegree));
}

constexpr auto spec(std::type_identity<Temperature>) {
  return message<Temperature>(0x03, "temperature",
                              field("valve_c", 1, &Temperature::valve_c, kCelsius),
                              field("sensor_c", 2, &Temperature::sensor_c, kCelsius));
}

constexpr auto spec(std::type_identity<Voltage>) {
  return message<Voltage>(0x04, "voltage", field("volts", 1, &Voltage::volts, kSupplyVolts));
}

constexpr auto spec(std::type_identity<RunCurrent>) {
  using M = RunCurrent;
  return message<M>(0x05, "run_current", field("amps", 1, &M::amps, kAmps),
                    field("last_running_amps", 3, &M::last_running_amps, kAmps));
}

constexpr auto spec(std::type_identity<DegreesPerSecond>) {
  using M = DegreesPerSecond;
  return message<M>(0x06, "degrees_per_second", field("dps", 1, &M::dps, kDegreesPerSecond),
                    field("direction", 3, &M::direction, kDirection));
}

constexpr auto spec(std::type_identity<SpeedDirection>) {
  using M = SpeedDirection;
  return message<M>(0x07, "speed_direction",
                    field("speed_percent", 1, &M::speed_percent, kSpeedPercent),
                    field("direction", 2, &M::direction, kDirection),
                    field("opening_direction", 3, &M::opening_direction, kRotation));
}

constexpr auto spec(std::type_identity<RunTime>) {
  return message<RunTime>(0x08, "run_time", field("seconds", 1, &RunTime::seconds, kSeconds32));
}

// The sheet labels this field "Run Time Seconds"; its byte table says Cycle Counts.
constexpr auto spec(std::type_identity<CycleCounts>) {
  return message<CycleCounts>(0x09, "cycle_counts",
                              field("count", 1, &CycleCounts::count, kCount32));
}

template <class Error>
constexpr auto voltage_error(std::string_view name) {
  return message<Error>(Error::kId, name, field("volts", 1, &Error::volts, kErrorVolts),
                        field("limit_volts", 3, &Error::limit_volts, kErrorVolts))
      .reports_error();
}
constexpr auto spec(std::type_identity<HighVoltageError>) {
  return voltage_error<HighVoltageError>("high_voltage_error");  // 0x10
}
constexpr auto spec(std::type_identity<LowVoltageError>) {
  return voltage_error<LowVoltageError>("low_voltage_error");  // 0x11
}

template <class Error>
constexpr auto current_error(std::string_view name) {
  return message<Error>(Error::kId, name, field("amps", 1, &Error::amps, kAmps),
                        field("limit_amps", 3, &Error::limit_amps, kAmps))
      .reports_error();
}
constexpr auto spec(std::type_identity<HighCurrentError>) {
  return current_error<HighCurrentError>("high_current_error");  // 0x12
}
constexpr auto spec(std::type_identity<LowCurrentError>) {
  return current_error<LowCurrentError>("low_current_error");  // 0x13
}

constexpr auto spec(std::type_identity<HighTemperatureError>) {
  using M = HighTemperatureError;
  return message<M>(0x14, "high_temperature_error",
                    field("temperature_c", 1, &M::temperature_c, kErrorCelsius),
                    field("limit_c", 2, &M::limit_c, kErrorCelsius))
      .reports_error();
}

constexpr auto spec(std::type_identity<MinDegreesPerSecondError>) {
  using M = MinDegreesPerSecondError;
  return message<M>(0x15, "min_degrees_per_second_error",
                    field("dps", 1, &M::dps, kDegreesPerSecond),
                    field("limit_dps", 3, &M::limit_dps, kDegreesPerSecond),
                    field("direction", 5, &M::direction, kDirection))
      .reports_error();
}

constexpr auto spec(std::type_identity<BaudRateReply>) {
  return message<BaudRateReply>(0x93, "baud_rate_reply",
                                MarkerByte<BaudRateReply>{"marker", 1, 0xA5},
                                field("bit_rate", 2, &BaudRateReply::bit_rate, kBitRate));
}

// ---- Controller to valve (0x18EF<valve>D5) --------------------------------------------------

// A request names the message that answers it.
template <class Reply>
inline constexpr std::uint8_t kReplyId = spec(std::type_identity<Reply>{}).id;

constexpr auto spec(std::type_identity<Stop>) { return message<Stop>(0x00, "stop").runs(); }

constexpr auto spec(std::type_identity<Manual>) {
  return message<Manual>(0x01, "manual",
                         field("speed_percent", 1, &Manual::speed_percent, kSpeedPercent),
                         field("direction", 2, &Manual::direction, kDirection))
      .runs();
}

constexpr auto spec(std::type_identity<TargetDegrees>) {
  using M = TargetDegrees;
  return message<M>(0x02, "target_degrees",
                    field("speed_percent", 1, &M::speed_percent, kSpeedPercent),
                    field("direction", 2, &M::direction, kTargetDirection),
                    field("degrees", 3, &M::degrees, kTenthsOfDegree))
      .runs();
}

constexpr auto spec(std::type_identity<DegreesFromPosition>) {
  using M = DegreesFromPosition;
  return message<M>(0x03, "degrees_from_position",
                    field("speed_percent", 1, &M::speed_percent, kSpeedPercent),
                    field("direction", 2, &M::direction, kDirection),
                    field("degrees", 3, &M::degrees, kTenthsOfDegree))
      .runs();
}

constexpr auto spec(std::type_identity<ClearErrors>) {
  return message<ClearErrors>(0x04, "clear_errors").runs();
}

constexpr auto spec(std::type_identity<MillisecondsToRun>) {
  using M = MillisecondsToRun;
  return message<M>(0x05, "milliseconds_to_run",
                    field("speed_percent", 1, &M::speed_percent, kSpeedPercent),
                    field("direction", 2, &M::direction, kDirection),
                    field("milliseconds", 3, &M::milliseconds, kMilliseconds))
      .runs();
}

constexpr auto spec(std::type_identity<RequestVersion>) {
  return message<RequestVersion>(0x10, "request_version")
      .answered_by(kReplyId<VersionInfo>)
      .asks_for_telemetry();
}

template <class Request, class Reply>
constexpr auto telemetry_request(std::string_view name) {
  return message<Request>(Request::kId, name,
                          field("resend_tenths", 1, &Request::resend_tenths, kResendTenths))
      .answered_by(kReplyId<Reply>)
      .asks_for_telemetry();
}

constexpr auto spec(std::type_identity<RequestPosition>) {
  return telemetry_request<RequestPosition, Position>("request_position");  // 0x11
}
constexpr auto spec(std::type_identity<RequestTemperature>) {
  return telemetry_request<RequestTemperature, Temperature>("request_temperature");  // 0x12
}
constexpr auto spec(std::type_identity<RequestVoltage>) {
  return telemetry_request<RequestVoltage, Voltage>("request_voltage");  // 0x13
}
constexpr auto spec(std::type_identity<RequestCurrent>) {
  return telemetry_request<RequestCurrent, RunCurrent>("request_current");  // 0x14
}
constexpr auto spec(std::type_identity<RequestDegreesPerSecond>) {
  return telemetry_request<RequestDegreesPerSecond, DegreesPerSecond>(
      "request_degrees_per_second");  // 0x15
}
constexpr auto spec(std::type_identity<RequestSpeedDirection>) {
  return telemetry_request<RequestSpeedDirection, SpeedDirection>(
      "request_speed_direction");  // 0x16
}
constexpr auto spec(std::type_identity<RequestRunTime>) {
  return telemetry_request<RequestRunTime, RunTime>("request_run_time");  // 0x17
}
constexpr auto spec(std::type_identity<RequestCycleCounts>) {
  return telemetry_request<RequestCycleCounts, CycleCounts>("request_cycle_counts");  // 0x18
}

constexpr auto spec(std::type_identity<BaudRate>) {
  // Set and request alike: the valve answers with its (new) bit rate.
  return message<BaudRate>(0x93, "baud_rate", field("action", 1, &BaudRate::action, kBaudAction),
                           field("bit_rate", 2, &BaudRate::bit_rate, kBitRate))
      .answered_by(kReplyId<BaudRateReply>);
}

}  // namespace teejet::codec::detail
