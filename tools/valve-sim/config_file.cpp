#include "config_file.hpp"

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <limits>
#include <optional>
#include <string_view>

#include "teejet/codec/table.hpp"
#include "teejet/yaml/reader.hpp"

namespace teejet::sim {
namespace {

using yaml::Reader;

// "valves[0]" + "dps" -> "valves[0].dps": the key named in messages.
std::string member(const std::string& key, std::string_view name) {
  std::string text = key;
  text += '.';
  text += name;
  return text;
}

// "valves" + 0 -> "valves[0]".
std::string element(const std::string& key, std::size_t index) {
  std::string text = key;
  text += '[';
  text += std::to_string(index);
  text += ']';
  return text;
}

// A finite number. Its range depends on the rest of the valve (closed below opened, ...), so
// validate() checks it when the valve is composed, naming the valve.
double any_number(const Reader& reader, const YAML::Node& node, const std::string& key) {
  return reader.number(node, key, std::numeric_limits<double>::lowest(),
                       std::numeric_limits<double>::max());
}

std::uint32_t read_serial(const Reader& reader, const YAML::Node& node, const std::string& key) {
  const auto parsed = codec::parse_serial(reader.scalar(node, key));
  if (!parsed) reader.fail(node, key, parsed.error().reason);
  return *parsed;
}

codec::SoftwareVersion read_version(const Reader& reader, const YAML::Node& node,
                                    const std::string& key) {
  const auto parsed = codec::parse_version(reader.scalar(node, key));
  if (!parsed) reader.fail(node, key, parsed.error().reason);
  return *parsed;
}

std::uint32_t read_bit_rate(const Reader& reader, const YAML::Node& node, const std::string& key) {
  const auto text = reader.scalar(node, key);
  if (text == "250000" || text == "250k") return codec::kBitRate250k;
  if (text == "500000" || text == "500k") return codec::kBitRate500k;
  reader.fail(node, key, "'" + text + "' is neither 250000 (250k) nor 500000 (500k)");
}

codec::Rotation read_rotation(const Reader& reader, const YAML::Node& node,
                              const std::string& key) {
  const auto text = reader.scalar(node, key);
  const auto rotation = parse_rotation(text);
  if (!rotation) reader.fail(node, key, "'" + text + "' is neither clockwise nor counterclockwise");
  return *rotation;
}

// {kind, value, limit[, direction]}; in the top-level `errors:` list also the serial, which
// `serial` then receives. Per-valve errors belong to their valve and have none.
InjectedError read_error(const Reader& reader, const YAML::Node& node, const std::string& key,
                         std::uint32_t* serial) {
  if (!node.IsMap()) reader.fail(node, key, "expected a mapping with kind, value and limit");
  reader.expect_keys(node, key, {"serial", "kind", "value", "limit", "direction"});
  if (!node["kind"] || !node["value"] || !node["limit"]) {
    reader.fail(node, key, "needs kind, value and limit");
  }
  if (serial == nullptr && node["serial"]) {
    reader.fail(node["serial"], key,
                "unknown key 'serial' (a valve's own errors are for that valve)");
  }
  if (serial != nullptr && !node["serial"]) reader.fail(node, key, "needs a serial");

  const auto kind = reader.scalar(node["kind"], member(key, "kind"));
  const double value = any_number(reader, node["value"], member(key, "value"));
  const double limit = any_number(reader, node["limit"], member(key, "limit"));
  std::optional<std::string> direction;
  if (const auto d = node["direction"]) direction = reader.scalar(d, member(key, "direction"));
  if (serial != nullptr) *serial = read_serial(reader, node["serial"], member(key, "serial"));
  const auto error = make_error(kind, value, limit, direction);
  if (!error) reader.fail(node, key, error.error().reason);
  return *error;
}

// The settings of one valve, or of every valve (`defaults:`, which has no serial).
ValveSettings read_settings(const Reader& reader, const YAML::Node& node, const std::string& key,
                            bool with_serial) {
  if (!node.IsMap()) reader.fail(node, key, "expected a mapping of settings");
  reader.expect_keys(
      node, key,
      {"serial", "part_number", "dps", "closed", "opened", "start", "opening_direction",
       "application_version", "bootloader_version", "volts", "valve_temperature",
       "sensor_temperature", "running_amps", "bit_rate", "errors"});
  ValveSettings s;
  if (const auto v = node["serial"]) {
    if (!with_serial) {
      reader.fail(v, key, "unknown key 'serial' (serials belong to valves: and hotplug: entries)");
    }
    s.serial = read_serial(reader, v, member(key, "serial"));
  } else if (with_serial) {
    reader.fail(node, key, "needs a serial");
  }
  if (const auto v = node["part_number"]) {
    s.part_number =
        static_cast<std::uint32_t>(reader.integer(v, member(key, "part_number"), 0, kMaxSerial));
  }
  if (const auto v = node["dps"]) s.degrees_per_second = any_number(reader, v, member(key, "dps"));
  if (const auto v = node["closed"])
    s.closed_degrees = any_number(reader, v, member(key, "closed"));
  if (const auto v = node["opened"])
    s.opened_degrees = any_number(reader, v, member(key, "opened"));
  if (const auto v = node["start"]) s.start_degrees = any_number(reader, v, member(key, "start"));
  if (const auto v = node["opening_direction"]) {
    s.opening_direction = read_rotation(reader, v, member(key, "opening_direction"));
  }
  if (const auto v = node["application_version"]) {
    s.application_version = read_version(reader, v, member(key, "application_version"));
  }
  if (const auto v = node["bootloader_version"]) {
    s.bootloader_version = read_version(reader, v, member(key, "bootloader_version"));
  }
  if (const auto v = node["volts"]) s.volts = any_number(reader, v, member(key, "volts"));
  if (const auto v = node["valve_temperature"]) {
    s.valve_temperature_c =
        static_cast<int>(reader.integer(v, member(key, "valve_temperature"), -127, 127));
  }
  if (const auto v = node["sensor_temperature"]) {
    s.sensor_temperature_c =
        static_cast<int>(reader.integer(v, member(key, "sensor_temperature"), -127, 127));
  }
  if (const auto v = node["running_amps"]) {
    s.running_amps = any_number(reader, v, member(key, "running_amps"));
  }
  if (const auto v = node["bit_rate"])
    s.bit_rate = read_bit_rate(reader, v, member(key, "bit_rate"));
  if (const auto v = node["errors"]) {
    const auto errors_key = member(key, "errors");
    reader.expect_list(v, errors_key, "errors");
    for (std::size_t i = 0; i < v.size(); ++i) {
      s.errors.push_back(read_error(reader, v[i], element(errors_key, i), nullptr));
    }
  }
  return s;
}

std::vector<ValveSettings> read_valves(const Reader& reader, const YAML::Node& node,
                                       const std::string& key) {
  reader.expect_list(node, key, "valves");
  std::vector<ValveSettings> valves;
  for (std::size_t i = 0; i < node.size(); ++i) {
    valves.push_back(read_settings(reader, node[i], element(key, i), true));
  }
  return valves;
}

std::vector<SerialError> read_errors(const Reader& reader, const YAML::Node& node,
                                     const std::string& key) {
  reader.expect_list(node, key, "errors");
  std::vector<SerialError> errors;
  for (std::size_t i = 0; i < node.size(); ++i) {
    SerialError entry;
    entry.error = read_error(reader, node[i], element(key, i), &entry.serial);
    errors.push_back(entry);
  }
  return errors;
}

}  // namespace

Result<ConfigFile> parse_config(const std::string& yaml_text, const std::string& origin) {
  return yaml::parse<ConfigFile>(
      origin, yaml_text, [](const Reader& reader, const YAML::Node& root) {
        ConfigFile file;
        if (root.IsNull()) return file;
        if (!root.IsMap()) {
          reader.fail(root, "top level", "expected a mapping (defaults, valves, hotplug, errors)");
        }
        reader.expect_keys(root, "top level", {"defaults", "valves", "hotplug", "errors"});
        if (const auto d = root["defaults"])
          file.defaults = read_settings(reader, d, "defaults", false);
        if (const auto v = root["valves"]) file.valves = read_valves(reader, v, "valves");
        if (const auto h = root["hotplug"]) file.hotplug = read_valves(reader, h, "hotplug");
        if (const auto e = root["errors"]) file.errors = read_errors(reader, e, "errors");
        return file;
      });
}

Result<ConfigFile> load_config(const std::string& path) {
  const auto text = yaml::read_file(path);
  if (!text) return text.error();
  return parse_config(*text, path);
}

}  // namespace teejet::sim
