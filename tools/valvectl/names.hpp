#pragma once

// The words valvectl uses for the IDL's enumerations, on its command line and in its output.
// Output names are snake_case like the gateway's own (bridge::to_string), so that text, JSON and
// the gateway's logs agree.

#include <optional>
#include <string_view>

#include "teejet/valve.h"

namespace teejet::valvectl {

// The WHAT of `valvectl request`: version position temperature voltage current dps speed
// run-time cycle-counts.
std::optional<Telemetry> parse_telemetry(std::string_view word);
std::string_view telemetry_word(Telemetry telemetry);  // the command-line word, "run-time"

// "open", "close" and, where `allow_shortest`, "shortest".
std::optional<Direction> parse_direction(std::string_view word, bool allow_shortest);
std::string_view to_string(Direction direction);

std::string_view to_string(ErrorKind kind);  // "high_voltage", ..., "min_degrees_per_second"
std::string_view to_string(BusState state);  // "error_active", ..., "bus_off", "down"

}  // namespace teejet::valvectl
