#pragma once

// The simulator's configuration as a user gives it: a YAML file (per-valve overrides, errors to
// inject, valves to add at run time) and command-line settings, composed into valve
// configurations. Format and precedence: docs/valve-sim.md.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "teejet/codec/result.hpp"
#include "teejet/sim/valve_config.hpp"

namespace teejet::sim {

// Settings that may or may not be given; apply_to() overwrites only those that are.
struct ValveSettings {
  std::optional<std::uint32_t> serial;
  std::optional<std::uint32_t> part_number;
  std::optional<double> degrees_per_second;
  std::optional<double> closed_degrees;
  std::optional<double> opened_degrees;
  std::optional<double> start_degrees;
  std::optional<codec::Rotation> opening_direction;
  std::optional<codec::SoftwareVersion> application_version;
  std::optional<codec::SoftwareVersion> bootloader_version;
  std::optional<double> volts;
  std::optional<int> valve_temperature_c;
  std::optional<int> sensor_temperature_c;
  std::optional<double> running_amps;
  std::optional<std::uint32_t> bit_rate;
  std::vector<InjectedError> errors;  // latched at power-up (or when added)

  void apply_to(ValveConfig& config) const;
};

struct ConfigFile {
  ValveSettings defaults;              // `defaults:` every valve
  std::vector<ValveSettings> valves;   // `valves:` each with a serial
  std::vector<ValveSettings> hotplug;  // `hotplug:` added one per SIGUSR1, in order
  std::vector<SerialError> errors;     // `errors:` each with a serial
};

// Parses the YAML text; `origin` names it in messages ("sim.yaml"). Unknown keys, wrong types
// and out-of-range values are refused with the line number.
codec::Result<ConfigFile> parse_config(const std::string& yaml_text, std::string_view origin);
codec::Result<ConfigFile> load_config(const std::string& path);

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
codec::Result<Setup> compose_setup(const CommandLine& command_line, const ConfigFile& file);

}  // namespace teejet::sim
