#pragma once

// The words valvectl's command line uses for the IDL's enumerations. Output uses the contract's
// own names (teejet/dds/names.hpp), so that text, JSON and the gateway's logs agree.

#include <optional>
#include <string_view>

#include "teejet/dds/names.hpp"
#include "teejet/valve.h"

namespace teejet::client {

// The WHAT of `valvectl request`: version position temperature voltage current dps speed
// run-time cycle-counts.
std::optional<Telemetry> parse_telemetry(std::string_view word);
std::string_view telemetry_word(Telemetry telemetry);  // the command-line word, "run-time"

// "open", "close" and, where `allow_shortest`, "shortest".
std::optional<Direction> parse_direction(std::string_view word, bool allow_shortest);

using dds::to_string;

}  // namespace teejet::client
