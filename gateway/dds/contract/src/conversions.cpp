#include "teejet/dds/conversions.hpp"

#include <array>
#include <cmath>
#include <string>

#include "teejet/codec/table.hpp"

namespace teejet::dds {
namespace {

template <class... Fs>
struct Overloaded : Fs... {
  using Fs::operator()...;
};
// C++20 deduces this from the aggregate alone; clang before 17 (the sanitizer builds) needs it.
template <class... Fs>
Overloaded(Fs...) -> Overloaded<Fs...>;

// ---- The rows: the IDL's enumerations against the codec's messages ---------------------------

// What each Telemetry value of the IDL asks for. The reply, the sample, the topic and every name
// follow from the request and the codec's table.
const auto kTelemetryRequests = std::to_array<std::pair<Telemetry, codec::ToValveMessage>>({
    {TELEMETRY_VERSION, codec::RequestVersion{}},
    {TELEMETRY_POSITION, codec::RequestPosition{}},
    {TELEMETRY_TEMPERATURE, codec::RequestTemperature{}},
    {TELEMETRY_VOLTAGE, codec::RequestVoltage{}},
    {TELEMETRY_CURRENT, codec::RequestCurrent{}},
    {TELEMETRY_DEGREES_PER_SECOND, codec::RequestDegreesPerSecond{}},
    {TELEMETRY_SPEED_DIRECTION, codec::RequestSpeedDirection{}},
    {TELEMETRY_RUN_TIME, codec::RequestRunTime{}},
    {TELEMETRY_CYCLE_COUNTS, codec::RequestCycleCounts{}},
});

// What each ErrorKind of the IDL is on the wire. A ValveError carries the error message's first
// field as its value, the second as its limit, and its direction if it has one.
const auto kErrorMessages = std::to_array<std::pair<ErrorKind, codec::FromValveMessage>>({
    {ERROR_HIGH_VOLTAGE, codec::HighVoltageError{}},
    {ERROR_LOW_VOLTAGE, codec::LowVoltageError{}},
    {ERROR_HIGH_CURRENT, codec::HighCurrentError{}},
    {ERROR_LOW_CURRENT, codec::LowCurrentError{}},
    {ERROR_HIGH_TEMPERATURE, codec::HighTemperatureError{}},
    {ERROR_MIN_DEGREES_PER_SECOND, codec::MinDegreesPerSecondError{}},
});

// The message each CommandKind but COMMAND_REQUEST sends (a request's is its telemetry's). A
// command fills the message's fields of the same name; a baud-rate request sends the one rate
// code the decoder accepts, whatever the command's bit_rate says.
struct CommandRow {
  CommandKind kind;
  codec::ToValveMessage message;
  bool takes_fields = true;
};
const std::array<CommandRow, 8> kCommands{{
    {COMMAND_STOP, codec::Stop{}},
    {COMMAND_MANUAL, codec::Manual{}},
    {COMMAND_TARGET_DEGREES, codec::TargetDegrees{}},
    {COMMAND_DEGREES_FROM_POSITION, codec::DegreesFromPosition{}},
    {COMMAND_CLEAR_ERRORS, codec::ClearErrors{}},
    {COMMAND_MILLISECONDS_TO_RUN, codec::MillisecondsToRun{}},
    {COMMAND_SET_BAUD_RATE, codec::BaudRate{codec::BaudAction::kSet, codec::kBitRate250k}},
    {COMMAND_REQUEST_BAUD_RATE, codec::BaudRate{codec::BaudAction::kRequest, codec::kBitRate250k},
     false},
}};

// ---- ValveCommand's fields by the codec's names ------------------------------------------------

// The command's value for a message field of the same name; nullopt for a field the IDL's
// command does not carry (the baud-rate marker).
std::optional<codec::FieldValue> command_field(const ValveCommand& command, std::string_view name) {
  if (name == "speed_percent") return std::int64_t{command.speed_percent()};
  if (name == "direction") {
    const auto word = direction_word(command.direction());
    if (word.empty()) return std::to_string(command.direction());  // refused by the codec
    return std::string(word);
  }
  if (name == "degrees") return static_cast<double>(command.degrees());
  if (name == "milliseconds") return std::int64_t{command.milliseconds()};
  if (name == "resend_tenths") return std::int64_t{command.resend_tenths()};
  if (name == "bit_rate") return std::int64_t{command.bit_rate()};
  return std::nullopt;
}

void set_command_field(ValveCommand& command, std::string_view name,
                       const codec::FieldValue& value) {
  const auto* integer = std::get_if<std::int64_t>(&value);
  if (name == "speed_percent" && integer)
    command.speed_percent(static_cast<std::uint8_t>(*integer));
  if (name == "milliseconds" && integer) command.milliseconds(static_cast<std::uint16_t>(*integer));
  if (name == "resend_tenths" && integer)
    command.resend_tenths(static_cast<std::uint8_t>(*integer));
  if (name == "bit_rate" && integer) command.bit_rate(static_cast<std::uint32_t>(*integer));
  if (const auto* real = std::get_if<double>(&value); real && name == "degrees") {
    command.degrees(static_cast<float>(*real));
  }
  if (const auto* word = std::get_if<std::string>(&value); word && name == "direction") {
    command.direction(direction_of(*word).value_or(DIRECTION_CLOSE));
  }
}

// The row of a message: the same id, and the same value in every field a command cannot carry
// (which tells a baud-rate set from a request).
const CommandRow* command_row(const codec::ToValveMessage& message) {
  for (const CommandRow& row : kCommands) {
    if (codec::message_id(row.message) != codec::message_id(message)) continue;
    bool same = true;
    for (const codec::FieldInfo& field : codec::describe(message).fields) {
      if (!command_field(ValveCommand{}, field.name)) {
        same = same && codec::field_value(row.message, field.name) ==
                           codec::field_value(message, field.name);
      }
    }
    if (same) return &row;
  }
  return nullptr;
}

Error undefined(const char* what, int value) {
  return field_error(ErrorCode::kInvalidValue, what, std::to_string(value) + " is undefined");
}

// ---- Samples ------------------------------------------------------------------------------

teejet::Direction to_idl(codec::Direction d) {
  return d == codec::Direction::kOpen ? DIRECTION_OPEN : DIRECTION_CLOSE;
}

codec::Direction to_codec(teejet::Direction d) {
  return d == DIRECTION_OPEN ? codec::Direction::kOpen : codec::Direction::kClose;
}

teejet::SoftwareVersion to_idl(const codec::SoftwareVersion& v) {
  teejet::SoftwareVersion out;
  out.major(static_cast<std::uint8_t>(v.major));
  out.minor(static_cast<std::uint8_t>(v.minor));
  out.test(v.test);
  return out;
}

codec::SoftwareVersion to_codec(const teejet::SoftwareVersion& v) {
  return {v.major(), v.minor(), v.test()};
}

template <class Sample>
Sample stamped(std::uint32_t serial, Timestamp received) {
  Sample sample;
  sample.serial(serial);
  sample.received_ns(unix_nanoseconds(received));
  return sample;
}

double number(const std::optional<codec::FieldValue>& value) {
  if (!value) return 0.0;
  if (const auto* integer = std::get_if<std::int64_t>(&*value))
    return static_cast<double>(*integer);
  if (const auto* real = std::get_if<double>(&*value)) return *real;
  return 0.0;
}

std::optional<TelemetrySample> error_sample(std::uint32_t serial,
                                            const codec::FromValveMessage& message,
                                            Timestamp received) {
  const auto kind = error_kind_of(message);
  if (!kind) return std::nullopt;
  const auto& fields = codec::describe(message).fields;
  auto sample = stamped<ValveError>(serial, received);
  sample.kind(*kind);
  sample.value(static_cast<float>(number(codec::field_value(message, fields.at(0).name))));
  sample.limit(static_cast<float>(number(codec::field_value(message, fields.at(1).name))));
  const auto direction = codec::field_value(message, "direction");
  const auto* word = direction ? std::get_if<std::string>(&*direction) : nullptr;
  sample.direction(word ? direction_of(*word).value_or(DIRECTION_CLOSE) : DIRECTION_CLOSE);
  return sample;
}

codec::FromValveMessage error_message(const ValveError& sample) {
  auto message = error_message_of(sample.kind()).value_or(codec::HighVoltageError{});
  const auto& fields = codec::describe(message).fields;
  // Each on its field's grid first: an error's whole degrees Celsius arrive as a float.
  const auto set = [&](const codec::FieldInfo& field, float value) {
    const double step = field.resolution;
    (void)codec::set_field(message, field.name, std::round(value / step) * step);
  };
  set(fields.at(0), sample.value());
  set(fields.at(1), sample.limit());
  if (codec::find_field(codec::describe(message), "direction") != nullptr) {
    (void)codec::set_field(message, "direction", std::string(direction_word(sample.direction())));
  }
  return message;
}

}  // namespace

std::optional<TelemetrySample> to_sample(std::uint32_t serial,
                                         const codec::FromValveMessage& message,
                                         Timestamp received) {
  return std::visit(Overloaded{
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
                          auto s = stamped<ValveCycleCounts>(serial, received);
                          s.count(m.count);
                          return s;
                        },
                        [&](const codec::BaudRateReply& m) -> std::optional<TelemetrySample> {
                          auto s = stamped<ValveBaudRate>(serial, received);
                          s.bit_rate(m.bit_rate);
                          return s;
                        },
                        // The errors, by the rows above; I'm Here feeds the directory, no topic.
                        [&](const auto& m) -> std::optional<TelemetrySample> {
                          return error_sample(serial, m, received);
                        },
                    },
                    message);
}

codec::FromValveMessage from_sample(const TelemetrySample& sample) {
  const auto message = std::visit(
      Overloaded{
          [](const ValveVersion& s) -> codec::FromValveMessage {
            return codec::VersionInfo{to_codec(s.application()), to_codec(s.bootloader())};
          },
          [](const ValvePosition& s) -> codec::FromValveMessage {
            return codec::Position{s.degrees()};
          },
          [](const ValveTemperature& s) -> codec::FromValveMessage {
            return codec::Temperature{s.valve_c(), s.sensor_c()};
          },
          [](const ValveVoltage& s) -> codec::FromValveMessage {
            return codec::Voltage{s.volts()};
          },
          [](const ValveCurrent& s) -> codec::FromValveMessage {
            return codec::RunCurrent{s.amps(), s.last_running_amps()};
          },
          [](const ValveDegreesPerSecond& s) -> codec::FromValveMessage {
            return codec::DegreesPerSecond{s.dps(), to_codec(s.direction())};
          },
          [](const ValveSpeedDirection& s) -> codec::FromValveMessage {
            return codec::SpeedDirection{s.speed_percent(), to_codec(s.direction()),
                                         s.opening_direction() == ROTATION_CLOCKWISE
                                             ? codec::Rotation::kClockwise
                                             : codec::Rotation::kCounterclockwise};
          },
          [](const ValveRunTime& s) -> codec::FromValveMessage {
            return codec::RunTime{s.seconds()};
          },
          [](const ValveCycleCounts& s) -> codec::FromValveMessage {
            return codec::CycleCounts{s.count()};
          },
          [](const ValveBaudRate& s) -> codec::FromValveMessage {
            return codec::BaudRateReply{s.bit_rate()};
          },
          [](const ValveError& s) -> codec::FromValveMessage { return error_message(s); },
      },
      sample);
  return codec::as_sent(message);
}

Result<codec::ToValveMessage> to_message(const ValveCommand& command) {
  std::optional<codec::ToValveMessage> message;
  bool takes_fields = true;
  if (command.kind() == COMMAND_REQUEST) {
    message = request_of(command.telemetry());
    if (!message) {
      return in_context("request", undefined("telemetry", static_cast<int>(command.telemetry())));
    }
    const bool resends = codec::find_field(codec::describe(*message), "resend_tenths") != nullptr;
    if (!resends && command.resend_tenths() != 0) {
      return in_context(codec::subject(*message),
                        field_error(ErrorCode::kInvalidValue, "resend_tenths",
                                    std::to_string(command.resend_tenths()) +
                                        " is not 0: the valve sends it once"));
    }
  } else {
    for (const CommandRow& row : kCommands) {
      if (row.kind == command.kind()) {
        message = row.message;
        takes_fields = row.takes_fields;
      }
    }
    if (!message) {
      return Error{ErrorCode::kInvalidValue,
                   "command kind " + std::to_string(command.kind()) + " is undefined"};
    }
  }
  if (!takes_fields) return *message;
  for (const codec::FieldInfo& field : codec::describe(*message).fields) {
    const auto value = command_field(command, field.name);
    if (!value) continue;
    if (auto set = codec::set_field(*message, field.name, *value); !set) return set.error();
  }
  return *message;
}

ValveCommand to_command(const codec::ToValveMessage& message) {
  ValveCommand command;
  if (const auto telemetry = telemetry_of(message)) {
    command.kind(COMMAND_REQUEST);
    command.telemetry(*telemetry);
  } else if (const CommandRow* row = command_row(message)) {
    command.kind(row->kind);
  }
  for (const codec::FieldInfo& field : codec::describe(message).fields) {
    if (const auto value = codec::field_value(message, field.name)) {
      set_command_field(command, field.name, *value);
    }
  }
  return command;
}

// The rows pair an IDL value with the codec message it stands for; both lookups walk them.
template <class Rows, class Value>
auto message_for(const Rows& rows, Value value)
    -> std::optional<typename Rows::value_type::second_type> {
  for (const auto& [row_value, message] : rows) {
    if (row_value == value) return message;
  }
  return std::nullopt;
}

template <class Rows, class Message>
auto value_for(const Rows& rows, const Message& message)
    -> std::optional<typename Rows::value_type::first_type> {
  for (const auto& [row_value, row_message] : rows) {
    if (codec::message_id(row_message) == codec::message_id(message)) return row_value;
  }
  return std::nullopt;
}

std::optional<codec::ToValveMessage> request_of(Telemetry telemetry) {
  return message_for(kTelemetryRequests, telemetry);
}

std::optional<Telemetry> telemetry_of(const codec::ToValveMessage& request) {
  return value_for(kTelemetryRequests, request);
}

std::optional<Telemetry> telemetry_of(std::string_view word) {
  const auto request = codec::telemetry_request(word);
  return request ? telemetry_of(*request) : std::nullopt;
}

std::optional<codec::FromValveMessage> error_message_of(ErrorKind kind) {
  return message_for(kErrorMessages, kind);
}

std::optional<ErrorKind> error_kind_of(const codec::FromValveMessage& message) {
  return value_for(kErrorMessages, message);
}

// The IDL's Direction values are the wire's, Target Degrees's direction byte included.
static_assert(DIRECTION_CLOSE == static_cast<int>(codec::TargetDirection::kClose) &&
              DIRECTION_OPEN == static_cast<int>(codec::TargetDirection::kOpen) &&
              DIRECTION_SHORTEST == static_cast<int>(codec::TargetDirection::kShortest));

std::string_view direction_word(Direction direction) {
  if (direction < 0 || direction > 0xFF) return {};
  const auto word = codec::to_string(static_cast<codec::TargetDirection>(direction));
  return word == "invalid" ? std::string_view{} : word;
}

std::optional<Direction> direction_of(std::string_view word) {
  for (const Direction direction : {DIRECTION_CLOSE, DIRECTION_OPEN, DIRECTION_SHORTEST}) {
    if (direction_word(direction) == word) return direction;
  }
  return std::nullopt;
}

AddressClaimState to_idl(isobus::ClaimState state) {
  switch (state) {
    case isobus::ClaimState::kOff:
      return CLAIM_OFF;
    case isobus::ClaimState::kClaiming:
      return CLAIM_CLAIMING;
    case isobus::ClaimState::kClaimed:
      return CLAIM_CLAIMED;
    case isobus::ClaimState::kYielded:
      return CLAIM_YIELDED;
  }
  return CLAIM_OFF;
}

isobus::ClaimState from_idl(AddressClaimState state) {
  switch (state) {
    case CLAIM_OFF:
      return isobus::ClaimState::kOff;
    case CLAIM_CLAIMING:
      return isobus::ClaimState::kClaiming;
    case CLAIM_CLAIMED:
      return isobus::ClaimState::kClaimed;
    case CLAIM_YIELDED:
      return isobus::ClaimState::kYielded;
  }
  return isobus::ClaimState::kOff;
}

}  // namespace teejet::dds
