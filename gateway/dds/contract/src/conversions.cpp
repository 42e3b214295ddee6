#include "teejet/dds/conversions.hpp"

#include <string>

#include "teejet/dds/names.hpp"

namespace teejet::dds {
namespace {

template <class... Fs>
struct Overloaded : Fs... {
  using Fs::operator()...;
};
// Spelled out for clang before 17, which does not deduce an aggregate's template arguments.
template <class... Fs>
Overloaded(Fs...) -> Overloaded<Fs...>;

teejet::Direction to_idl(codec::Direction d) {
  return d == codec::Direction::kOpen ? DIRECTION_OPEN : DIRECTION_CLOSE;
}

teejet::SoftwareVersion to_idl(const codec::SoftwareVersion& v) {
  teejet::SoftwareVersion out;
  out.major(static_cast<std::uint8_t>(v.major));
  out.minor(static_cast<std::uint8_t>(v.minor));
  out.test(v.test);
  return out;
}

template <class Sample>
Sample stamped(std::uint32_t serial, Timestamp received) {
  Sample sample;
  sample.serial(serial);
  sample.received_ns(unix_nanoseconds(received));
  return sample;
}

ValveError error_sample(std::uint32_t serial, Timestamp received, ErrorKind kind, double value,
                        double limit, teejet::Direction direction = DIRECTION_CLOSE) {
  auto sample = stamped<ValveError>(serial, received);
  sample.kind(kind);
  sample.value(static_cast<float>(value));
  sample.limit(static_cast<float>(limit));
  sample.direction(direction);
  return sample;
}

Error invalid(const ValveCommand& command, const std::string& why) {
  return Error{ErrorCode::kInvalidValue, std::string(to_string(command.kind())) + ": " + why};
}

Result<codec::Direction> drive_direction(const ValveCommand& command) {
  switch (command.direction()) {
    case DIRECTION_OPEN:
      return codec::Direction::kOpen;
    case DIRECTION_CLOSE:
      return codec::Direction::kClose;
    case DIRECTION_SHORTEST:
      return invalid(command, "direction SHORTEST exists only for Target Degrees");
  }
  return invalid(command, "direction " + std::to_string(command.direction()) + " is undefined");
}

Result<codec::ToValveMessage> telemetry_request(const ValveCommand& command) {
  const unsigned resend = command.resend_tenths();
  switch (command.telemetry()) {
    case TELEMETRY_VERSION:
      if (resend != 0) return invalid(command, "version is sent once; resend_tenths must be 0");
      return codec::ToValveMessage{codec::RequestVersion{}};
    case TELEMETRY_POSITION:
      return codec::ToValveMessage{codec::RequestPosition{resend}};
    case TELEMETRY_TEMPERATURE:
      return codec::ToValveMessage{codec::RequestTemperature{resend}};
    case TELEMETRY_VOLTAGE:
      return codec::ToValveMessage{codec::RequestVoltage{resend}};
    case TELEMETRY_CURRENT:
      return codec::ToValveMessage{codec::RequestCurrent{resend}};
    case TELEMETRY_DEGREES_PER_SECOND:
      return codec::ToValveMessage{codec::RequestDegreesPerSecond{resend}};
    case TELEMETRY_SPEED_DIRECTION:
      return codec::ToValveMessage{codec::RequestSpeedDirection{resend}};
    case TELEMETRY_RUN_TIME:
      return codec::ToValveMessage{codec::RequestRunTime{resend}};
    case TELEMETRY_CYCLE_COUNTS:
      return codec::ToValveMessage{codec::RequestCycleCounts{resend}};
  }
  return invalid(command, "telemetry " + std::to_string(command.telemetry()) + " is undefined");
}

}  // namespace

std::optional<TelemetrySample> to_sample(std::uint32_t serial,
                                         const codec::FromValveMessage& message,
                                         Timestamp received) {
  return std::visit(
      Overloaded{
          [](const codec::IAmHere&) -> std::optional<TelemetrySample> { return std::nullopt; },
          [&](const codec::VersionInfo& m) -> std::optional<TelemetrySample> {
            auto s = stamped<ValveVersion>(serial, received);
            s.application(to_idl(m.application));
            s.bootloader(to_idl(m.bootloader));
            return s;
          },
          [&](const codec::Position& m) -> std::optional<TelemetrySample> {
            auto s = stamped<ValvePosition>(serial, received);
            s.degrees(static_cast<float>(m.degrees));
            return s;
          },
          [&](const codec::Temperature& m) -> std::optional<TelemetrySample> {
            auto s = stamped<ValveTemperature>(serial, received);
            s.valve_c(static_cast<std::int8_t>(m.valve_c));
            s.sensor_c(static_cast<std::int8_t>(m.sensor_c));
            return s;
          },
          [&](const codec::Voltage& m) -> std::optional<TelemetrySample> {
            auto s = stamped<ValveVoltage>(serial, received);
            s.volts(static_cast<float>(m.volts));
            return s;
          },
          [&](const codec::RunCurrent& m) -> std::optional<TelemetrySample> {
            auto s = stamped<ValveCurrent>(serial, received);
            s.amps(static_cast<float>(m.amps));
            s.last_running_amps(static_cast<float>(m.last_running_amps));
            return s;
          },
          [&](const codec::DegreesPerSecond& m) -> std::optional<TelemetrySample> {
            auto s = stamped<ValveDegreesPerSecond>(serial, received);
            s.dps(static_cast<std::uint16_t>(m.dps));
            s.direction(to_idl(m.direction));
            return s;
          },
          [&](const codec::SpeedDirection& m) -> std::optional<TelemetrySample> {
            auto s = stamped<ValveSpeedDirection>(serial, received);
            s.speed_percent(static_cast<std::uint8_t>(m.speed_percent));
            s.direction(to_idl(m.direction));
            s.opening_direction(m.opening_direction == codec::Rotation::kClockwise
                                    ? ROTATION_CLOCKWISE
                                    : ROTATION_COUNTERCLOCKWISE);
            return s;
          },
          [&](const codec::RunTime& m) -> std::optional<TelemetrySample> {
            auto s = stamped<ValveRunTime>(serial, received);
            s.seconds(m.seconds);
            return s;
          },
          [&](const codec::CycleCounts& m) -> std::optional<TelemetrySample> {
            auto s = stamped<ValveCycleCount>(serial, received);
            s.count(m.count);
            return s;
          },
          [&](const codec::BaudRateReply& m) -> std::optional<TelemetrySample> {
            auto s = stamped<ValveBaudRate>(serial, received);
            s.bit_rate(m.bit_rate);
            return s;
          },
          [&](const codec::HighVoltageError& m) -> std::optional<TelemetrySample> {
            return error_sample(serial, received, ERROR_HIGH_VOLTAGE, m.volts, m.limit_volts);
          },
          [&](const codec::LowVoltageError& m) -> std::optional<TelemetrySample> {
            return error_sample(serial, received, ERROR_LOW_VOLTAGE, m.volts, m.limit_volts);
          },
          [&](const codec::HighCurrentError& m) -> std::optional<TelemetrySample> {
            return error_sample(serial, received, ERROR_HIGH_CURRENT, m.amps, m.limit_amps);
          },
          [&](const codec::LowCurrentError& m) -> std::optional<TelemetrySample> {
            return error_sample(serial, received, ERROR_LOW_CURRENT, m.amps, m.limit_amps);
          },
          [&](const codec::HighTemperatureError& m) -> std::optional<TelemetrySample> {
            return error_sample(serial, received, ERROR_HIGH_TEMPERATURE, m.temperature_c,
                                m.limit_c);
          },
          [&](const codec::MinDegreesPerSecondError& m) -> std::optional<TelemetrySample> {
            return error_sample(serial, received, ERROR_MIN_DEGREES_PER_SECOND, m.dps, m.limit_dps,
                                to_idl(m.direction));
          },
      },
      message);
}

Result<codec::ToValveMessage> to_message(const ValveCommand& command) {
  const unsigned speed = command.speed_percent();
  switch (command.kind()) {
    case COMMAND_STOP:
      return codec::ToValveMessage{codec::Stop{}};
    case COMMAND_CLEAR_ERRORS:
      return codec::ToValveMessage{codec::ClearErrors{}};
    case COMMAND_MANUAL: {
      auto direction = drive_direction(command);
      if (!direction) return direction.error();
      return codec::ToValveMessage{codec::Manual{speed, *direction}};
    }
    case COMMAND_TARGET_DEGREES: {
      codec::TargetDirection direction{};
      switch (command.direction()) {
        case DIRECTION_OPEN:
          direction = codec::TargetDirection::kOpen;
          break;
        case DIRECTION_CLOSE:
          direction = codec::TargetDirection::kClose;
          break;
        case DIRECTION_SHORTEST:
          direction = codec::TargetDirection::kShortest;
          break;
        default:
          return invalid(command,
                         "direction " + std::to_string(command.direction()) + " is undefined");
      }
      return codec::ToValveMessage{codec::TargetDegrees{speed, direction, command.degrees()}};
    }
    case COMMAND_DEGREES_FROM_POSITION: {
      auto direction = drive_direction(command);
      if (!direction) return direction.error();
      return codec::ToValveMessage{
          codec::DegreesFromPosition{speed, *direction, command.degrees()}};
    }
    case COMMAND_MILLISECONDS_TO_RUN: {
      auto direction = drive_direction(command);
      if (!direction) return direction.error();
      return codec::ToValveMessage{
          codec::MillisecondsToRun{speed, *direction, command.milliseconds()}};
    }
    case COMMAND_REQUEST:
      return telemetry_request(command);
    case COMMAND_SET_BAUD_RATE:
      return codec::ToValveMessage{codec::BaudRate{codec::BaudAction::kSet, command.bit_rate()}};
    case COMMAND_REQUEST_BAUD_RATE:
      return codec::ToValveMessage{
          codec::BaudRate{codec::BaudAction::kRequest, codec::kBitRate250k}};
  }
  return Error{ErrorCode::kInvalidValue,
               "command kind " + std::to_string(command.kind()) + " is undefined"};
}

ValveCommand to_command(const codec::ToValveMessage& message) {
  ValveCommand command;
  const auto drive = [&](CommandKind kind, unsigned speed, codec::Direction direction) {
    command.kind(kind);
    command.speed_percent(static_cast<std::uint8_t>(speed));
    command.direction(direction == codec::Direction::kOpen ? DIRECTION_OPEN : DIRECTION_CLOSE);
  };
  const auto request = [&](Telemetry telemetry, unsigned resend) {
    command.kind(COMMAND_REQUEST);
    command.telemetry(telemetry);
    command.resend_tenths(static_cast<std::uint8_t>(resend));
  };
  std::visit(
      Overloaded{
          [&](const codec::Stop&) { command.kind(COMMAND_STOP); },
          [&](const codec::Manual& m) { drive(COMMAND_MANUAL, m.speed_percent, m.direction); },
          [&](const codec::TargetDegrees& m) {
            command.kind(COMMAND_TARGET_DEGREES);
            command.speed_percent(static_cast<std::uint8_t>(m.speed_percent));
            command.direction(m.direction == codec::TargetDirection::kOpen    ? DIRECTION_OPEN
                              : m.direction == codec::TargetDirection::kClose ? DIRECTION_CLOSE
                                                                              : DIRECTION_SHORTEST);
            command.degrees(static_cast<float>(m.degrees));
          },
          [&](const codec::DegreesFromPosition& m) {
            drive(COMMAND_DEGREES_FROM_POSITION, m.speed_percent, m.direction);
            command.degrees(static_cast<float>(m.degrees));
          },
          [&](const codec::ClearErrors&) { command.kind(COMMAND_CLEAR_ERRORS); },
          [&](const codec::MillisecondsToRun& m) {
            drive(COMMAND_MILLISECONDS_TO_RUN, m.speed_percent, m.direction);
            command.milliseconds(static_cast<std::uint16_t>(m.milliseconds));
          },
          [&](const codec::RequestVersion&) { request(TELEMETRY_VERSION, 0); },
          [&](const codec::RequestPosition& m) { request(TELEMETRY_POSITION, m.resend_tenths); },
          [&](const codec::RequestTemperature& m) {
            request(TELEMETRY_TEMPERATURE, m.resend_tenths);
          },
          [&](const codec::RequestVoltage& m) { request(TELEMETRY_VOLTAGE, m.resend_tenths); },
          [&](const codec::RequestCurrent& m) { request(TELEMETRY_CURRENT, m.resend_tenths); },
          [&](const codec::RequestDegreesPerSecond& m) {
            request(TELEMETRY_DEGREES_PER_SECOND, m.resend_tenths);
          },
          [&](const codec::RequestSpeedDirection& m) {
            request(TELEMETRY_SPEED_DIRECTION, m.resend_tenths);
          },
          [&](const codec::RequestRunTime& m) { request(TELEMETRY_RUN_TIME, m.resend_tenths); },
          [&](const codec::RequestCycleCounts& m) {
            request(TELEMETRY_CYCLE_COUNTS, m.resend_tenths);
          },
          [&](const codec::BaudRate& m) {
            if (m.action == codec::BaudAction::kSet) {
              command.kind(COMMAND_SET_BAUD_RATE);
              command.bit_rate(m.bit_rate);
            } else {
              command.kind(COMMAND_REQUEST_BAUD_RATE);
            }
          },
      },
      message);
  return command;
}

}  // namespace teejet::dds
