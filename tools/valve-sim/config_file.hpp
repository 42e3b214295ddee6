#pragma once

// valve-sim's YAML config file (docs/valve-sim.md, "Config file") read into plain settings:
// defaults, per-valve settings, errors to inject, valves to add at run time. Read with the
// shared YAML reader (gateway/yaml), so every mistake is refused with the file, the line and the
// key: unknown keys, keys given twice, wrong types, numbers that are not numbers. The ranges of
// valve settings are checked when they are composed into valves (setup.hpp), which names the
// valve; an injected error is checked here, where its line is known.

#include <string>
#include <vector>

#include "teejet/core/result.hpp"
#include "teejet/sim/valve_config.hpp"
#include "valve_settings.hpp"

namespace teejet::sim {

struct ConfigFile {
  ValveSettings defaults;              // `defaults:` every valve
  std::vector<ValveSettings> valves;   // `valves:` each with a serial
  std::vector<ValveSettings> hotplug;  // `hotplug:` added one per SIGUSR1, in order
  std::vector<SerialError> errors;     // `errors:` each with a serial
};

// Reads the YAML text; `origin` names it in messages ("sim.yaml:3: valves[0]: ...").
Result<ConfigFile> parse_config(const std::string& yaml_text, const std::string& origin);
// Reads the file at `path`, named by its path in messages.
Result<ConfigFile> load_config(const std::string& path);

}  // namespace teejet::sim
