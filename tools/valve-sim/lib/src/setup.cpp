#include "teejet/sim/setup.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "teejet/codec/codec.hpp"
#include "teejet/sim/valve_bank.hpp"

namespace teejet::sim {
namespace {

// Thrown inside the parser only; parse_config() turns it into a Result.
struct ConfigError {
  std::string reason;
};

class Parser {
 public:
  explicit Parser(std::string_view origin) : origin_(origin) {}

  [[noreturn]] void fail(const YAML::Node& node, const std::string& where,
                         const std::string& what) const {
    std::string text = origin_;
    if (node.Mark().line >= 0) text += ":" + std::to_string(node.Mark().line + 1);
    throw ConfigError{text + ": " + where + ": " + what};
  }

  std::string scalar(const YAML::Node& node, const std::string& where) const {
    if (!node.IsScalar()) fail(node, where, "expected a single value");
    return node.Scalar();
  }

  double number(const YAML::Node& node, const std::string& where) const {
    const auto text = scalar(node, where);
    try {
      std::size_t used = 0;
      const double value = std::stod(text, &used);
      if (used == text.size() && std::isfinite(value)) return value;
    } catch (const std::exception&) {
    }
    fail(node, where, "'" + text + "' is not a number");
  }

  long long integer(const YAML::Node& node, const std::string& where, long long min,
                    long long max) const {
    const double value = number(node, where);
    if (value != std::floor(value) || value < static_cast<double>(min) ||
        value > static_cast<double>(max)) {
      fail(node, where,
           scalar(node, where) + " is not a whole number from " + std::to_string(min) + " to " +
               std::to_string(max));
    }
    return static_cast<long long>(value);
  }

  std::uint32_t serial(const YAML::Node& node, const std::string& where) const {
    const auto parsed = codec::parse_serial(scalar(node, where));
    if (!parsed) fail(node, where, parsed.error().reason);
    return *parsed;
  }

  codec::SoftwareVersion version(const YAML::Node& node, const std::string& where) const {
    const auto parsed = parse_version(scalar(node, where));
    if (!parsed) fail(node, where, parsed.error().reason);
    return *parsed;
  }

  std::uint32_t bit_rate(const YAML::Node& node, const std::string& where) const {
    const auto text = scalar(node, where);
    if (text == "250000" || text == "250k") return codec::kBitRate250k;
    if (text == "500000" || text == "500k") return codec::kBitRate500k;
    fail(node, where, "'" + text + "' is neither 250000 (250k) nor 500000 (500k)");
  }

  InjectedError error(const YAML::Node& node, const std::string& where,
                      std::optional<std::uint32_t>* serial_out) const {
    if (!node.IsMap()) fail(node, where, "expected a mapping with kind, value and limit");
    InjectedError error;
    bool has_kind = false;
    bool has_value = false;
    bool has_limit = false;
    for (const auto& item : node) {
      const auto key = scalar(item.first, where);
      const auto here = where + "." + key;
      if (key == "kind") {
        const auto kind = parse_error_kind(scalar(item.second, here));
        if (!kind) {
          fail(item.second, here,
               "unknown error kind '" + item.second.Scalar() +
                   "' (high-voltage, low-voltage, high-current, low-current, high-temperature, "
                   "min-dps)");
        }
        error.kind = *kind;
        has_kind = true;
      } else if (key == "value") {
        error.value = number(item.second, here);
        has_value = true;
      } else if (key == "limit") {
        error.limit = number(item.second, here);
        has_limit = true;
      } else if (key == "direction") {
        const auto text = scalar(item.second, here);
        if (text == "open") {
          error.direction = codec::Direction::kOpen;
        } else if (text == "close") {
          error.direction = codec::Direction::kClose;
        } else {
          fail(item.second, here, "'" + text + "' is neither open nor close");
        }
      } else if (key == "serial" && serial_out != nullptr) {
        *serial_out = serial(item.second, here);
      } else {
        fail(item.first, where, "unknown key '" + key + "'");
      }
    }
    if (!has_kind || !has_value || !has_limit) fail(node, where, "needs kind, value and limit");
    if (serial_out != nullptr && !serial_out->has_value()) fail(node, where, "needs a serial");
    if (const auto valid = validate(error); !valid) fail(node, where, valid.reason());
    return error;
  }

  ValveSettings settings(const YAML::Node& node, const std::string& where,
                         bool needs_serial) const {
    if (!node.IsMap()) fail(node, where, "expected a mapping of settings");
    ValveSettings s;
    for (const auto& item : node) {
      const auto key = scalar(item.first, where);
      const auto here = where + "." + key;
      const auto& value = item.second;
      if (key == "serial" && needs_serial) {
        s.serial = serial(value, here);
      } else if (key == "part_number") {
        s.part_number = static_cast<std::uint32_t>(integer(value, here, 0, kMaxSerial));
      } else if (key == "dps") {
        s.degrees_per_second = number(value, here);
      } else if (key == "closed") {
        s.closed_degrees = number(value, here);
      } else if (key == "opened") {
        s.opened_degrees = number(value, here);
      } else if (key == "start") {
        s.start_degrees = number(value, here);
      } else if (key == "opening_direction") {
        const auto rotation = parse_rotation(scalar(value, here));
        if (!rotation) {
          fail(value, here, "'" + value.Scalar() + "' is neither clockwise nor counterclockwise");
        }
        s.opening_direction = rotation;
      } else if (key == "application_version") {
        s.application_version = version(value, here);
      } else if (key == "bootloader_version") {
        s.bootloader_version = version(value, here);
      } else if (key == "volts") {
        s.volts = number(value, here);
      } else if (key == "valve_temperature") {
        s.valve_temperature_c = static_cast<int>(integer(value, here, -127, 127));
      } else if (key == "sensor_temperature") {
        s.sensor_temperature_c = static_cast<int>(integer(value, here, -127, 127));
      } else if (key == "running_amps") {
        s.running_amps = number(value, here);
      } else if (key == "bit_rate") {
        s.bit_rate = bit_rate(value, here);
      } else if (key == "errors") {
        if (!value.IsSequence()) fail(value, here, "expected a list of errors");
        for (std::size_t i = 0; i < value.size(); ++i) {
          s.errors.push_back(error(value[i], here + "[" + std::to_string(i) + "]", nullptr));
        }
      } else {
        fail(item.first, where, "unknown key '" + key + "'");
      }
    }
    if (needs_serial && !s.serial) fail(node, where, "needs a serial");
    return s;
  }

  std::vector<ValveSettings> valve_list(const YAML::Node& node, const std::string& where) const {
    if (!node.IsSequence()) fail(node, where, "expected a list of valves");
    std::vector<ValveSettings> list;
    for (std::size_t i = 0; i < node.size(); ++i) {
      list.push_back(settings(node[i], where + "[" + std::to_string(i) + "]", true));
    }
    return list;
  }

  ConfigFile file(const YAML::Node& root) const {
    ConfigFile file;
    if (root.IsNull()) return file;
    if (!root.IsMap()) fail(root, "top level", "expected a mapping (defaults, valves, ...)");
    for (const auto& item : root) {
      const auto key = scalar(item.first, "top level");
      if (key == "defaults") {
        file.defaults = settings(item.second, key, false);
      } else if (key == "valves") {
        file.valves = valve_list(item.second, key);
      } else if (key == "hotplug") {
        file.hotplug = valve_list(item.second, key);
      } else if (key == "errors") {
        if (!item.second.IsSequence()) fail(item.second, key, "expected a list of errors");
        for (std::size_t i = 0; i < item.second.size(); ++i) {
          std::optional<std::uint32_t> serial;
          auto error = this->error(item.second[i], key + "[" + std::to_string(i) + "]", &serial);
          file.errors.push_back({*serial, error});
        }
      } else {
        fail(item.first, "top level",
             "unknown key '" + key + "' (defaults, valves, hotplug, errors)");
      }
    }
    return file;
  }

 private:
  std::string origin_;
};

codec::Error setup_error(std::string reason) {
  return codec::Error{codec::ErrorCode::kInvalidValue, std::move(reason)};
}

}  // namespace

void ValveSettings::apply_to(ValveConfig& config) const {
  if (serial) config.serial = *serial;
  if (part_number) config.part_number = *part_number;
  if (degrees_per_second) config.degrees_per_second = *degrees_per_second;
  if (closed_degrees) config.closed_degrees = *closed_degrees;
  if (opened_degrees) config.opened_degrees = *opened_degrees;
  if (start_degrees) config.start_degrees = *start_degrees;
  if (opening_direction) config.opening_direction = *opening_direction;
  if (application_version) config.application_version = *application_version;
  if (bootloader_version) config.bootloader_version = *bootloader_version;
  if (volts) config.volts = *volts;
  if (valve_temperature_c) config.valve_temperature_c = *valve_temperature_c;
  if (sensor_temperature_c) config.sensor_temperature_c = *sensor_temperature_c;
  if (running_amps) config.running_amps = *running_amps;
  if (bit_rate) config.bit_rate = *bit_rate;
}

codec::Result<ConfigFile> parse_config(const std::string& yaml_text, std::string_view origin) {
  const Parser parser(origin);
  try {
    return parser.file(YAML::Load(yaml_text));
  } catch (const ConfigError& error) {
    return setup_error(error.reason);
  } catch (const YAML::Exception& error) {
    return setup_error(std::string(origin) + ": " + error.what());
  }
}

codec::Result<ConfigFile> load_config(const std::string& path) {
  std::ifstream in(path);
  if (!in) return setup_error("cannot read config file '" + path + "'");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) return setup_error("error reading config file '" + path + "'");
  return parse_config(text.str(), path);
}

codec::Result<Setup> compose_setup(const CommandLine& command_line, const ConfigFile& file) {
  if (command_line.valve_count && !command_line.serials.empty()) {
    return setup_error("--valves and --serials exclude each other");
  }
  ValveConfig base;
  file.defaults.apply_to(base);
  command_line.settings.apply_to(base);

  // Which valves make the bank.
  std::vector<std::uint32_t> serials;
  const bool from_command_line = command_line.valve_count || !command_line.serials.empty();
  if (command_line.valve_count) {
    const unsigned count = *command_line.valve_count;
    if (count < 1 || count > kMaxValves) {
      return setup_error("--valves " + std::to_string(count) + ": give 1 to " +
                         std::to_string(kMaxValves) + " (the addresses 0xD8-0xF7)");
    }
    for (unsigned i = 1; i <= count; ++i) serials.push_back(i);
  } else if (!command_line.serials.empty()) {
    serials = command_line.serials;
  } else {
    for (const auto& entry : file.valves) serials.push_back(*entry.serial);
  }
  if (serials.empty()) {
    return setup_error(
        "no valves to simulate: give --valves N, --serials LIST or a --config "
        "file with valves");
  }
  if (serials.size() > kMaxValves) {
    return setup_error(std::to_string(serials.size()) + " valves do not fit the " +
                       std::to_string(kMaxValves) + " addresses 0xD8-0xF7");
  }
  std::set<std::uint32_t> in_bank;
  for (const auto serial : serials) {
    if (!in_bank.insert(serial).second) {
      return setup_error("serial " + codec::format_serial(serial) + " is given twice");
    }
  }

  // The file's entries, by serial.
  std::set<std::uint32_t> seen;
  for (const auto& entry : file.valves) {
    if (!seen.insert(*entry.serial).second) {
      return setup_error("the config file lists " + codec::format_serial(*entry.serial) +
                         " twice under valves");
    }
    if (from_command_line && !in_bank.contains(*entry.serial)) {
      return setup_error("the config file has settings for " + codec::format_serial(*entry.serial) +
                         ", which is not one of the valves given by --valves/--serials");
    }
  }
  auto entry_for = [&](std::uint32_t serial) -> const ValveSettings* {
    for (const auto& entry : file.valves) {
      if (*entry.serial == serial) return &entry;
    }
    return nullptr;
  };

  Setup setup;
  setup.base = base;
  setup.base_errors = file.defaults.errors;
  for (const auto serial : serials) {
    ValveConfig config = base;
    config.serial = serial;
    const auto* entry = entry_for(serial);
    if (entry) entry->apply_to(config);
    if (const auto valid = validate(config); !valid) return setup_error(valid.reason());
    setup.valves.push_back(config);
    for (const auto& error : file.defaults.errors) setup.errors.push_back({serial, error});
    if (entry) {
      for (const auto& error : entry->errors) setup.errors.push_back({serial, error});
    }
  }

  std::set<std::uint32_t> hotplug_serials;
  for (const auto& entry : file.hotplug) {
    const auto serial = *entry.serial;
    if (in_bank.contains(serial) || !hotplug_serials.insert(serial).second) {
      return setup_error("hotplug valve " + codec::format_serial(serial) +
                         " is already in the bank or listed twice");
    }
    ValveConfig config = base;
    entry.apply_to(config);
    if (const auto valid = validate(config); !valid) {
      return setup_error("hotplug " + valid.reason());
    }
    setup.hotplug.push_back(config);
    for (const auto& error : file.defaults.errors) setup.hotplug_errors.push_back({serial, error});
    for (const auto& error : entry.errors) setup.hotplug_errors.push_back({serial, error});
  }

  for (const auto* errors : {&file.errors, &command_line.errors}) {
    for (const auto& serial_error : *errors) {
      if (in_bank.contains(serial_error.serial)) {
        setup.errors.push_back(serial_error);
      } else if (hotplug_serials.contains(serial_error.serial)) {
        setup.hotplug_errors.push_back(serial_error);
      } else {
        return setup_error("error " + std::string(to_string(serial_error.error.kind)) + " for " +
                           codec::format_serial(serial_error.serial) +
                           ", which is not a simulated valve");
      }
    }
  }
  return setup;
}

}  // namespace teejet::sim
