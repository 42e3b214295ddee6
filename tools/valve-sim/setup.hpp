#pragma once

// The bank valve-sim simulates: the command line and the config file (config_file.hpp) composed
// into validated valve configurations and errors. Precedence: docs/valve-sim.md.

#include <cstdint>
#include <optional>
#include <vector>

#include "config_file.hpp"
#include "teejet/core/result.hpp"
#include "teejet/sim/valve_config.hpp"
#include "valve_settings.hpp"

namespace teejet::sim {

// What the user asked for on the command line.
struct CommandLine {
  std::optional<unsigned> valve_count;  // --valves N: serials 1..N
  std::vector<std::uint32_t> serials;   // --serials
  ValveSettings settings;               // --dps, --closed, --opened, ...
  std::vector<SerialError> errors;      // --inject-error
};

struct Setup {
  ValveConfig base;  // defaults, file defaults and command line: for added valves
  std::vector<InjectedError> base_errors;  // the file's `defaults: errors:`
  std::vector<ValveConfig> valves;         // validated, at most 32
  std::vector<SerialError> errors;         // validated, each for a valve of the bank
  std::vector<ValveConfig> hotplug;  // validated, with their own errors left in hotplug_errors
  std::vector<SerialError> hotplug_errors;
};

// Composes the bank. Precedence, weakest first: built-in defaults, the file's `defaults:`, the
// command-line settings, the file's entry for the serial. The valve set is --valves or --serials
// when given (the file's `valves:` entries must then name valves of that set), else the file's
// `valves:`. Refuses an empty or oversized bank, duplicate serials, invalid values and errors
// for serials that are not in the bank.
Result<Setup> compose_setup(const CommandLine& command_line, const ConfigFile& file);

}  // namespace teejet::sim
