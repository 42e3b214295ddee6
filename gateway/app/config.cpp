#include "config.hpp"

#include <yaml-cpp/yaml.h>

#include <charconv>
#include <fstream>
#include <set>
#include <sstream>

#include "teejet/codec/codec.hpp"

namespace teejet::gateway {
namespace {

using codec::Error;
using codec::ErrorCode;

struct ConfigError {
  std::string message;
};

[[noreturn]] void fail(const YAML::Node& node, const std::string& what) {
  const auto mark = node.Mark();
  throw ConfigError{(mark.line >= 0 ? "line " + std::to_string(mark.line + 1) + ": " : "") + what};
}

void only_keys(const YAML::Node& map, const std::set<std::string>& allowed,
               const std::string& section) {
  if (!map.IsMap()) fail(map, section + " must be a mapping");
  for (const auto& entry : map) {
    const auto key = entry.first.as<std::string>();
    if (!allowed.contains(key)) fail(entry.first, "unknown key '" + key + "' in " + section);
  }
}

template <class T>
T read(const YAML::Node& node, const std::string& name) {
  try {
    return node.as<T>();
  } catch (const YAML::Exception&) {
    fail(node, name + " has the wrong type: '" + YAML::Dump(node) + "'");
  }
}

double read_seconds(const YAML::Node& node, const std::string& name) {
  const double seconds = read<double>(node, name);
  if (!(seconds > 0)) fail(node, name + " must be greater than 0");
  return seconds;
}

std::chrono::nanoseconds to_duration(double seconds) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
      std::chrono::duration<double>(seconds));
}

// poll: {version: once, position: 1, temperature: 10, run_time: off, ...}
std::vector<codec::ToValveMessage> read_poll(const YAML::Node& node) {
  only_keys(node,
            {"version", "position", "temperature", "voltage", "current", "degrees_per_second",
             "speed_direction", "run_time", "cycle_counts"},
            "poll");
  // Start from the defaults so that a file naming one entry changes only that one.
  std::map<std::string, std::optional<unsigned>> periods{
      {"position", 1},  {"temperature", 10},        {"voltage", 10},
      {"current", 10},  {"degrees_per_second", 10}, {"speed_direction", 10},
      {"run_time", 50}, {"cycle_counts", 50}};
  bool version = true;
  for (const auto& entry : node) {
    const auto name = entry.first.as<std::string>();
    const auto text = read<std::string>(entry.second, "poll." + name);
    if (name == "version") {
      if (text != "once" && text != "off") fail(entry.second, "poll.version is 'once' or 'off'");
      version = text == "once";
      continue;
    }
    if (text == "off") {
      periods[name] = std::nullopt;
      continue;
    }
    const unsigned tenths = text == "once" ? 0 : read<unsigned>(entry.second, "poll." + name);
    if (tenths > 255) fail(entry.second, "poll." + name + " is at most 255 tenths of a second");
    periods[name] = tenths;
  }
  std::vector<codec::ToValveMessage> schedule;
  if (version) schedule.emplace_back(codec::RequestVersion{});
  const auto add = [&](const std::string& name, auto request) {
    if (const auto tenths = periods.at(name)) {
      request.resend_tenths = *tenths;
      schedule.emplace_back(request);
    }
  };
  add("position", codec::RequestPosition{});
  add("temperature", codec::RequestTemperature{});
  add("voltage", codec::RequestVoltage{});
  add("current", codec::RequestCurrent{});
  add("degrees_per_second", codec::RequestDegreesPerSecond{});
  add("speed_direction", codec::RequestSpeedDirection{});
  add("run_time", codec::RequestRunTime{});
  add("cycle_counts", codec::RequestCycleCounts{});
  return schedule;
}

bridge::ValveLimits read_limits(const YAML::Node& node, const std::string& section) {
  only_keys(node, {"closed_deg", "opened_deg"}, section);
  bridge::ValveLimits limits;
  if (node["closed_deg"]) limits.closed_degrees = read<double>(node["closed_deg"], "closed_deg");
  if (node["opened_deg"]) limits.opened_degrees = read<double>(node["opened_deg"], "opened_deg");
  if (!(limits.closed_degrees >= 0 && limits.closed_degrees < limits.opened_degrees &&
        (limits.opened_degrees <= 340 || limits.opened_degrees == 360))) {
    fail(node, section + ": need 0 <= closed_deg < opened_deg, opened_deg <= 340 or = 360");
  }
  return limits;
}

void apply(const YAML::Node& root, GatewayConfig& config) {
  if (root.IsNull()) return;
  only_keys(root, {"gateway", "commands", "poll", "valves", "simulator"}, "the file");
  if (const auto g = root["gateway"]) {
    only_keys(g,
              {"name", "can", "domain", "profile", "offline_after_s", "stop_valves_on_exit",
               "on_commander_lost", "allow_baud_change"},
              "gateway");
    if (g["name"]) config.bridge.gateway_name = read<std::string>(g["name"], "gateway.name");
    if (g["can"]) config.can = read<std::string>(g["can"], "gateway.can");
    if (g["domain"]) config.domain = read<int>(g["domain"], "gateway.domain");
    if (g["profile"]) config.profile_file = read<std::string>(g["profile"], "gateway.profile");
    if (g["offline_after_s"]) {
      config.bridge.offline_after =
          to_duration(read_seconds(g["offline_after_s"], "gateway.offline_after_s"));
    }
    if (g["stop_valves_on_exit"]) {
      config.stop_valves_on_exit = read<bool>(g["stop_valves_on_exit"], "stop_valves_on_exit");
    }
    if (g["on_commander_lost"]) {
      const auto action = read<std::string>(g["on_commander_lost"], "on_commander_lost");
      if (action != "stop" && action != "ignore") {
        fail(g["on_commander_lost"], "gateway.on_commander_lost is 'stop' or 'ignore'");
      }
      config.on_commander_lost =
          action == "stop" ? OnCommanderLost::kStopItsValves : OnCommanderLost::kIgnore;
    }
    if (g["allow_baud_change"]) {
      config.bridge.allow_baud_change = read<bool>(g["allow_baud_change"], "allow_baud_change");
    }
  }
  if (const auto c = root["commands"]) {
    only_keys(c, {"completion_tolerance_deg", "reply_timeout_s", "move_margin_s", "assumed_dps"},
              "commands");
    if (c["completion_tolerance_deg"]) {
      config.bridge.completion_tolerance_degrees =
          read<double>(c["completion_tolerance_deg"], "completion_tolerance_deg");
    }
    if (c["reply_timeout_s"]) {
      config.bridge.reply_timeout =
          to_duration(read_seconds(c["reply_timeout_s"], "reply_timeout_s"));
    }
    if (c["move_margin_s"]) {
      config.bridge.move_margin = to_duration(read_seconds(c["move_margin_s"], "move_margin_s"));
    }
    if (c["assumed_dps"])
      config.bridge.assumed_dps = read<unsigned>(c["assumed_dps"], "assumed_dps");
  }
  if (const auto p = root["poll"]) config.bridge.poll = read_poll(p);
  if (const auto v = root["valves"]) {
    if (!v.IsMap()) fail(v, "valves must be a mapping of 'default' or serials to limits");
    for (const auto& entry : v) {
      const auto key = entry.first.as<std::string>();
      if (key == "default") {
        config.bridge.default_limits = read_limits(entry.second, "valves.default");
        continue;
      }
      const auto serial = codec::parse_serial(key);
      if (!serial) fail(entry.first, "valves: " + serial.error().reason);
      config.bridge.limits[*serial] = read_limits(entry.second, "valves." + key);
    }
  }
  if (const auto s = root["simulator"]) {
    only_keys(s, {"first_serial", "dps", "closed_deg", "opened_deg"}, "simulator");
    if (s["first_serial"]) {
      const auto serial = codec::parse_serial(read<std::string>(s["first_serial"], "first_serial"));
      if (!serial) fail(s["first_serial"], "simulator.first_serial: " + serial.error().reason);
      config.sim_first_serial = *serial;
    }
    if (s["dps"]) config.sim_degrees_per_second = read<double>(s["dps"], "simulator.dps");
    if (s["closed_deg"]) config.sim_closed_degrees = read<double>(s["closed_deg"], "closed_deg");
    if (s["opened_deg"]) config.sim_opened_degrees = read<double>(s["opened_deg"], "opened_deg");
  }
}

}  // namespace

codec::Result<GatewayConfig> parse_config(const std::string& yaml, const std::string& source,
                                          GatewayConfig base) {
  try {
    apply(YAML::Load(yaml), base);
    return base;
  } catch (const ConfigError& error) {
    return Error{ErrorCode::kInvalidValue, source + ": " + error.message};
  } catch (const YAML::Exception& error) {
    return Error{ErrorCode::kInvalidValue, source + ": " + error.what()};
  }
}

codec::Result<GatewayConfig> load_config_file(const std::string& path, GatewayConfig base) {
  std::ifstream file(path);
  if (!file) return Error{ErrorCode::kInvalidValue, "cannot read config file '" + path + "'"};
  std::stringstream text;
  text << file.rdbuf();
  return parse_config(text.str(), path, std::move(base));
}

codec::Result<std::optional<int>> simulated_valve_count(const std::string& can) {
  constexpr std::string_view kPrefix = "sim:";
  if (!can.starts_with(kPrefix)) return std::optional<int>{};
  const std::string_view digits = std::string_view(can).substr(kPrefix.size());
  int count = 0;
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), count);
  if (digits.empty() || ec != std::errc() || end != digits.data() + digits.size() || count < 1 ||
      count > 32) {
    return Error{ErrorCode::kOutOfRange,
                 "--can " + can + ": sim:N takes 1 to 32 valves (one per address 0xD8..0xF7)"};
  }
  return std::optional<int>{count};
}

}  // namespace teejet::gateway
