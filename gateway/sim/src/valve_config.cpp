#include "teejet/sim/valve_config.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <string>
#include <vector>

#include "teejet/codec/table.hpp"

namespace teejet::sim {
namespace {

std::string number(double value) {
  std::array<char, 32> text{};
  const auto [end, ec] = std::to_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() ? std::string(text.data(), end) : std::string("?");
}

Status invalid(const ValveConfig& config, const std::string& what) {
  return Error{ErrorCode::kInvalidValue, codec::format_serial(config.serial) + ": " + what};
}

std::vector<std::string_view> split(std::string_view text, char separator) {
  std::vector<std::string_view> parts;
  for (;;) {
    const auto at = text.find(separator);
    parts.push_back(text.substr(0, at));
    if (at == std::string_view::npos) return parts;
    text.remove_prefix(at + 1);
  }
}

std::optional<double> parse_double(std::string_view text) {
  double value = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size() ||
      !std::isfinite(value)) {
    return std::nullopt;
  }
  return value;
}

Error value_error(std::string reason) { return Error{ErrorCode::kInvalidValue, std::move(reason)}; }

// The values a valve with `config` reports, in the messages that carry them: the codec refuses
// what the sheet does not allow, naming the field.
Status check_reported_values(const ValveConfig& config) {
  const std::array<codec::FromValveMessage, 7> reported{
      codec::IAmHere{config.part_number, config.serial, false},
      codec::VersionInfo{config.application_version, config.bootloader_version},
      codec::Voltage{config.volts},
      codec::Temperature{config.valve_temperature_c, config.sensor_temperature_c},
      codec::RunCurrent{config.running_amps, config.running_amps},
      codec::DegreesPerSecond{static_cast<unsigned>(std::lround(config.degrees_per_second)),
                              codec::Direction::kOpen},
      codec::BaudRateReply{config.bit_rate}};
  for (const auto& message : reported) {
    if (const auto frame = codec::encode(codec::kFirstValveAddress, message); !frame) {
      return invalid(config, frame.error().field + " " + frame.error().complaint);
    }
  }
  return {};
}

}  // namespace

Status validate(const ValveConfig& config) {
  if (config.serial > kMaxSerial) {
    return Error{ErrorCode::kInvalidValue, "serial " + std::to_string(config.serial) +
                                               " does not fit the 24 bits of I'm Here"};
  }
  const double dps = config.degrees_per_second;
  if (!std::isfinite(dps) || dps <= 0.0) {
    return invalid(config, "degrees per second " + number(dps) + " must be above 0");
  }
  if (const auto reported = check_reported_values(config); !reported) return reported;
  if (const auto limits = codec::check_valve_limits(config.closed_degrees, config.opened_degrees);
      !limits) {
    return invalid(config, limits.error().reason);
  }
  const double start = config.start_position();
  const double closed = config.closed_degrees;
  const double opened = config.opened_degrees;
  if (!std::isfinite(start)) return invalid(config, "start position must be a number");
  if (config.full_turn() ? (start < 0.0 || start >= kFullTurnDegrees)
                         : (start < closed || start > opened)) {
    std::string range = "[0, 360)";
    if (!config.full_turn())
      range =
          std::string("[").append(number(closed)).append(", ").append(number(opened)).append("]");
    return invalid(config, "start position " + number(start) + " is outside " + range);
  }
  return {};
}

Result<InjectedError> make_error(std::string_view kind, double value, double limit,
                                 std::optional<std::string_view> direction) {
  auto error = codec::error_message(kind);
  if (!error) {
    std::string kinds;
    for (const std::string_view name : codec::error_kinds()) {
      if (!kinds.empty()) kinds += ", ";
      kinds += name;
    }
    std::string reason = "unknown error kind '";
    reason.append(kind).append("' (").append(kinds).append(")");
    return value_error(std::move(reason));
  }
  const auto& fields = codec::describe(*error).fields;
  for (const auto& [field, number] :
       {std::pair{fields.at(0).name, value}, std::pair{fields.at(1).name, limit}}) {
    if (auto set = codec::set_field(*error, field, number); !set) return set.error();
  }
  if (direction) {
    if (codec::find_field(codec::describe(*error), "direction") == nullptr) {
      std::string reason(codec::error_kind(*error));
      return value_error(reason.append(" takes no DIRECTION"));
    }
    if (auto set = codec::set_field(*error, "direction", std::string(*direction)); !set) {
      return set.error();
    }
  }
  return *error;
}

Status validate(const InjectedError& error) {
  if (codec::error_kind(error).empty()) {
    std::string reason(codec::message_name(error));
    return value_error(reason.append(" is not an error message"));
  }
  // The codec knows every range of the sheet: what it refuses to encode is invalid.
  const auto frame = codec::encode(codec::kFirstValveAddress, error);
  if (!frame) return frame.error();
  return {};
}

Result<SerialError> parse_error_spec(std::string_view text) {
  const std::string original(text);
  const auto parts = split(text, ':');
  if (parts.size() != 4 && parts.size() != 5) {
    return value_error("'" + original +
                       "' is not SERIAL:KIND:VALUE:LIMIT[:DIRECTION], e.g. "
                       "TJV000001:high_voltage:16.2:15.5");
  }
  const auto serial = codec::parse_serial(parts[0]);
  if (!serial) return value_error("'" + original + "': " + serial.error().reason);
  const auto value = parse_double(parts[2]);
  const auto limit = parse_double(parts[3]);
  if (!value || !limit) return value_error("'" + original + "': VALUE and LIMIT must be numbers");
  const auto error = make_error(parts[1], *value, *limit,
                                parts.size() == 5 ? std::optional(parts[4]) : std::nullopt);
  if (!error) return value_error("'" + original + "': " + error.error().reason);
  return SerialError{*serial, *error};
}

std::optional<codec::Rotation> parse_rotation(std::string_view text) {
  if (text == "clockwise" || text == "cw") return codec::Rotation::kClockwise;
  if (text == "counterclockwise" || text == "ccw") return codec::Rotation::kCounterclockwise;
  return std::nullopt;
}

}  // namespace teejet::sim
