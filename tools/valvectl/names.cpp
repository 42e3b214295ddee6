#include "names.hpp"

#include <array>
#include <utility>

namespace teejet::valvectl {
namespace {

constexpr std::array<std::pair<std::string_view, Telemetry>, 9> kTelemetryWords{{
    {"version", TELEMETRY_VERSION},
    {"position", TELEMETRY_POSITION},
    {"temperature", TELEMETRY_TEMPERATURE},
    {"voltage", TELEMETRY_VOLTAGE},
    {"current", TELEMETRY_CURRENT},
    {"dps", TELEMETRY_DEGREES_PER_SECOND},
    {"speed", TELEMETRY_SPEED_DIRECTION},
    {"run-time", TELEMETRY_RUN_TIME},
    {"cycle-counts", TELEMETRY_CYCLE_COUNTS},
}};

}  // namespace

std::optional<Telemetry> parse_telemetry(std::string_view word) {
  for (const auto& [name, telemetry] : kTelemetryWords) {
    if (name == word) return telemetry;
  }
  return std::nullopt;
}

std::string_view telemetry_word(Telemetry telemetry) {
  for (const auto& [name, value] : kTelemetryWords) {
    if (value == telemetry) return name;
  }
  return "unknown";
}

std::optional<Direction> parse_direction(std::string_view word, bool allow_shortest) {
  if (word == "open") return DIRECTION_OPEN;
  if (word == "close") return DIRECTION_CLOSE;
  if (word == "shortest" && allow_shortest) return DIRECTION_SHORTEST;
  return std::nullopt;
}

std::string_view to_string(Direction direction) {
  switch (direction) {
    case DIRECTION_OPEN:
      return "open";
    case DIRECTION_CLOSE:
      return "close";
    case DIRECTION_SHORTEST:
      return "shortest";
  }
  return "unknown";
}

std::string_view to_string(ErrorKind kind) {
  switch (kind) {
    case ERROR_HIGH_VOLTAGE:
      return "high_voltage";
    case ERROR_LOW_VOLTAGE:
      return "low_voltage";
    case ERROR_HIGH_CURRENT:
      return "high_current";
    case ERROR_LOW_CURRENT:
      return "low_current";
    case ERROR_HIGH_TEMPERATURE:
      return "high_temperature";
    case ERROR_MIN_DEGREES_PER_SECOND:
      return "min_degrees_per_second";
  }
  return "unknown";
}

std::string_view to_string(BusState state) {
  switch (state) {
    case BUS_ERROR_ACTIVE:
      return "error_active";
    case BUS_ERROR_WARNING:
      return "error_warning";
    case BUS_ERROR_PASSIVE:
      return "error_passive";
    case BUS_OFF:
      return "bus_off";
    case BUS_DOWN:
      return "down";
  }
  return "unknown";
}

}  // namespace teejet::valvectl
