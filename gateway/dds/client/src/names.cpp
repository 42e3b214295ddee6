#include "teejet/client/names.hpp"

#include <array>
#include <utility>

namespace teejet::client {
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

}  // namespace teejet::client
