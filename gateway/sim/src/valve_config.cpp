#include "teejet/sim/valve_config.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <string>
#include <vector>

#include "teejet/codec/codec.hpp"

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

bool whole(double value) { return std::isfinite(value) && value == std::floor(value); }

struct KindName {
  ErrorKind kind;
  std::string_view name;
};
constexpr std::array<KindName, kErrorKindCount> kKindNames{{
    {ErrorKind::kHighVoltage, "high-voltage"},
    {ErrorKind::kLowVoltage, "low-voltage"},
    {ErrorKind::kHighCurrent, "high-current"},
    {ErrorKind::kLowCurrent, "low-current"},
    {ErrorKind::kHighTemperature, "high-temperature"},
    {ErrorKind::kMinDegreesPerSecond, "min-dps"},
}};

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

}  // namespace

Status validate(const ValveConfig& config) {
  if (config.serial > kMaxSerial) {
    return Error{ErrorCode::kInvalidValue, "serial " + std::to_string(config.serial) +
                                               " does not fit the 24 bits of I'm Here"};
  }
  if (config.part_number > kMaxSerial) {
    return invalid(config,
                   "part number " + std::to_string(config.part_number) + " does not fit 24 bits");
  }
  const double dps = config.degrees_per_second;
  if (!std::isfinite(dps) || dps <= 0.0 || dps > 359.0) {
    return invalid(config, "degrees per second " + number(dps) + " is outside (0, 359]");
  }
  const double closed = config.closed_degrees;
  const double opened = config.opened_degrees;
  if (!std::isfinite(closed) || !std::isfinite(opened)) {
    return invalid(config, "closed and opened degrees must be numbers");
  }
  if (config.full_turn()) {
    if (opened != kFullTurnDegrees) {
      return invalid(config, "opened degrees " + number(opened) +
                                 " is neither 360 (full turn) nor at most 340");
    }
    if (closed < 0.0 || closed >= kFullTurnDegrees) {
      return invalid(config, "closed degrees " + number(closed) + " is outside [0, 360)");
    }
  } else {
    if (opened > kMaxLimitedOpenedDegrees) {
      return invalid(config, "opened degrees " + number(opened) +
                                 " is neither 360 (full turn) nor at most 340 (the sheet)");
    }
    if (closed < 0.0 || closed >= opened) {
      return invalid(config, "closed degrees " + number(closed) +
                                 " must be at least 0 and below opened degrees " + number(opened));
    }
  }
  const double start = config.start_position();
  if (!std::isfinite(start)) return invalid(config, "start position must be a number");
  if (config.full_turn() ? (start < 0.0 || start >= kFullTurnDegrees)
                         : (start < closed || start > opened)) {
    return invalid(config,
                   "start position " + number(start) + " is outside " +
                       (config.full_turn() ? std::string("[0, 360)")
                                           : "[" + number(closed) + ", " + number(opened) + "]"));
  }
  for (const auto* version : {&config.application_version, &config.bootloader_version}) {
    if (version->major > 255 || version->minor > 255) {
      return invalid(config, "version " + codec::format_version(*version) +
                                 ": major and minor must be 0 to 255");
    }
  }
  if (!(config.volts >= 0.0 && config.volts <= 16.5)) {
    return invalid(config, "volts " + number(config.volts) + " is outside 0 to 16.5");
  }
  for (const int celsius : {config.valve_temperature_c, config.sensor_temperature_c}) {
    if (celsius < -127 || celsius > 127) {
      return invalid(config,
                     "temperature " + std::to_string(celsius) + " °C is outside -127 to 127");
    }
  }
  if (!(config.running_amps >= 0.0 && config.running_amps <= 655.35)) {
    return invalid(config,
                   "running amps " + number(config.running_amps) + " is outside 0 to 655.35");
  }
  if (config.bit_rate != codec::kBitRate250k && config.bit_rate != codec::kBitRate500k) {
    return invalid(config,
                   "bit rate " + std::to_string(config.bit_rate) + " is neither 250000 nor 500000");
  }
  return {};
}

std::string_view to_string(ErrorKind kind) {
  for (const auto& entry : kKindNames) {
    if (entry.kind == kind) return entry.name;
  }
  return "unknown";
}

std::optional<ErrorKind> parse_error_kind(std::string_view text) {
  std::string normalized(text);
  for (char& c : normalized) {
    if (c == '_') c = '-';
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  for (const auto& entry : kKindNames) {
    if (entry.name == normalized) return entry.kind;
  }
  return std::nullopt;
}

codec::FromValveMessage error_message(const InjectedError& error) {
  const auto whole_number = [](double value) { return static_cast<int>(std::lround(value)); };
  const auto whole_unsigned = [](double value) {
    return value <= 0.0 ? 0u : static_cast<unsigned>(std::lround(value));
  };
  switch (error.kind) {
    case ErrorKind::kHighVoltage:
      return codec::HighVoltageError{error.value, error.limit};
    case ErrorKind::kLowVoltage:
      return codec::LowVoltageError{error.value, error.limit};
    case ErrorKind::kHighCurrent:
      return codec::HighCurrentError{error.value, error.limit};
    case ErrorKind::kLowCurrent:
      return codec::LowCurrentError{error.value, error.limit};
    case ErrorKind::kHighTemperature:
      return codec::HighTemperatureError{whole_number(error.value), whole_number(error.limit)};
    case ErrorKind::kMinDegreesPerSecond:
      return codec::MinDegreesPerSecondError{whole_unsigned(error.value),
                                             whole_unsigned(error.limit), error.direction};
  }
  return codec::HighVoltageError{error.value, error.limit};
}

Status validate(const InjectedError& error) {
  const std::string kind(to_string(error.kind));
  if (!std::isfinite(error.value) || !std::isfinite(error.limit) || error.value < 0.0 ||
      error.limit < 0.0) {
    return Error{ErrorCode::kInvalidValue,
                 kind + ": value and limit must be numbers of at least 0"};
  }
  if ((error.kind == ErrorKind::kHighTemperature ||
       error.kind == ErrorKind::kMinDegreesPerSecond) &&
      (!whole(error.value) || !whole(error.limit))) {
    return Error{ErrorCode::kInvalidValue, kind + ": value and limit must be whole numbers"};
  }
  // The codec knows every range of the sheet: what it refuses to encode is invalid.
  const auto frame = codec::encode(codec::kFirstValveAddress, error_message(error));
  if (!frame) return Error{ErrorCode::kInvalidValue, kind + ": " + frame.error().reason};
  return {};
}

Result<SerialError> parse_error_spec(std::string_view text) {
  const std::string original(text);
  const auto parts = split(text, ':');
  if (parts.size() != 4 && parts.size() != 5) {
    return value_error("'" + original +
                       "' is not SERIAL:KIND:VALUE:LIMIT[:DIRECTION], e.g. "
                       "TJV000001:high-voltage:16.2:15.5");
  }
  SerialError result;
  const auto serial = codec::parse_serial(parts[0]);
  if (!serial) return value_error("'" + original + "': " + serial.error().reason);
  result.serial = *serial;
  const auto kind = parse_error_kind(parts[1]);
  if (!kind) {
    return value_error("'" + original + "': unknown error kind '" + std::string(parts[1]) +
                       "' (high-voltage, low-voltage, high-current, low-current, "
                       "high-temperature, min-dps)");
  }
  result.error.kind = *kind;
  const auto value = parse_double(parts[2]);
  const auto limit = parse_double(parts[3]);
  if (!value || !limit) {
    return value_error("'" + original + "': VALUE and LIMIT must be numbers");
  }
  result.error.value = *value;
  result.error.limit = *limit;
  if (parts.size() == 5) {
    if (*kind != ErrorKind::kMinDegreesPerSecond) {
      return value_error("'" + original + "': only min-dps takes a DIRECTION");
    }
    if (parts[4] == "open") {
      result.error.direction = codec::Direction::kOpen;
    } else if (parts[4] == "close") {
      result.error.direction = codec::Direction::kClose;
    } else {
      return value_error("'" + original + "': DIRECTION must be open or close");
    }
  }
  if (const auto valid = validate(result.error); !valid) {
    return value_error("'" + original + "': " + valid.error().reason);
  }
  return result;
}

Result<codec::SoftwareVersion> parse_version(std::string_view text) {
  const std::string original(text);
  const auto fail = [&] {
    return value_error("version '" + original +
                       "' is not MAJOR.MINOR with an optional test character, e.g. 1.02e");
  };
  const auto dot = text.find('.');
  if (dot == std::string_view::npos) return fail();
  unsigned major = 0;
  unsigned minor = 0;
  const auto major_text = text.substr(0, dot);
  auto [major_end, major_ec] =
      std::from_chars(major_text.data(), major_text.data() + major_text.size(), major);
  if (major_text.empty() || major_ec != std::errc() ||
      major_end != major_text.data() + major_text.size() || major > 255) {
    return fail();
  }
  auto rest = text.substr(dot + 1);
  auto [minor_end, minor_ec] = std::from_chars(rest.data(), rest.data() + rest.size(), minor);
  if (minor_ec != std::errc() || minor > 255) return fail();
  rest.remove_prefix(static_cast<std::size_t>(minor_end - rest.data()));
  char test = 0;
  if (rest.size() == 1 && rest[0] >= 0x21 && rest[0] <= 0x7E) {
    test = rest[0];
  } else if (!rest.empty()) {
    return fail();
  }
  return codec::SoftwareVersion{major, minor, test};
}

std::optional<codec::Rotation> parse_rotation(std::string_view text) {
  if (text == "clockwise" || text == "cw") return codec::Rotation::kClockwise;
  if (text == "counterclockwise" || text == "ccw") return codec::Rotation::kCounterclockwise;
  return std::nullopt;
}

}  // namespace teejet::sim
