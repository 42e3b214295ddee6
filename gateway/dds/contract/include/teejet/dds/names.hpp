#pragma once

// snake_case names of the IDL's enumerations: how the gateway logs them, valvectl prints them and
// JSON carries them, so that all three agree. Directions, error kinds and telemetry are the
// codec's words (teejet/codec/table.hpp). Values the IDL does not define read "unknown".

#include <string_view>

#include "teejet/valve.h"

namespace teejet::dds {

std::string_view to_string(CommandKind kind);     // "stop", "target_degrees", ...
std::string_view to_string(CommandState state);   // "accepted", ..., "superseded"
std::string_view to_string(Direction direction);  // "close", "open", "shortest"
std::string_view to_string(ErrorKind kind);       // "high_voltage", ..., "min_degrees_per_second"
std::string_view to_string(Telemetry telemetry);  // "version", "position", ..., "cycle_counts"
std::string_view to_string(AddressClaimState state);  // "off", "claiming", "claimed", "yielded"
std::string_view to_string(BusState state);           // "error_active", ..., "bus_off", "down"
// The layout's words (teejet/layout/layout.hpp, held equal by bridge_tests).
std::string_view to_string(LocationRole role);        // "section", "master", "rate", "other"
std::string_view to_string(LocationState state);      // "ok", "missing", "empty"
std::string_view to_string(LayoutChangeKind kind);    // "assign", "unassign"
std::string_view to_string(LayoutChangeState state);  // "applied", "rejected"

}  // namespace teejet::dds
