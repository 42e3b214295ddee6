#include "teejet/gateway/config.hpp"

#include <algorithm>
#include <filesystem>
#include <map>
#include <sstream>

#include "teejet/codec/table.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/isobus/name.hpp"
#include "teejet/layout/layout_file.hpp"
#include "teejet/yaml/reader.hpp"

namespace teejet::gateway {
namespace {

using yaml::Reader;

// Upper bounds that keep every duration far from overflowing and still cover any real use.
constexpr double kMaxSeconds = 3600.0;
// Wider than any real mismatch, and still well short of "anywhere on the dial".
constexpr double kMaxToleranceDegrees = 45.0;
// Per valve: a whole 1 Mbit/s bus's frames per second, and what one valve's command queue holds
// (topics.cpp: 256 commands per valve).
constexpr double kMaxCommandRate = 10'000.0;
constexpr long long kMaxCommandBurst = 256;

std::string format_seconds(Duration duration) {
  std::ostringstream text;
  text << std::chrono::duration<double>(duration).count();
  return text.str();
}

// A field's range as the codec's table gives it.
template <class Message>
const codec::FieldInfo& field_of(const Message& message, std::string_view name) {
  return *codec::find_field(codec::describe(message), name);
}

// Degrees as a valve's position can be: 0 to 359.9.
double max_position_degrees() { return field_of(codec::TargetDegrees{}, "degrees").max; }

// poll: {version: once, position: 1, temperature: 10, run_time: off, ...}: the keys are the
// codec's telemetry names, so every telemetry request of the table can be polled.
std::vector<codec::ToValveMessage> read_poll(const Reader& reader, const YAML::Node& node) {
  // Starts from the default schedule, so that a file naming one entry changes only that one.
  std::map<std::string_view, std::optional<codec::ToValveMessage>> schedule;
  for (const auto& request : bridge::default_poll_schedule()) {
    schedule[codec::subject(request)] = request;
  }
  const auto& names = codec::telemetry_names();
  reader.expect_keys(node, "poll", names);
  for (const auto& entry : node) {
    const auto name = entry.first.Scalar();
    const auto key = "poll." + name;
    auto request = *codec::telemetry_request(name);
    auto& slot = schedule[codec::subject(request)];
    const auto* resend = codec::find_field(codec::describe(request), "resend_tenths");
    if (resend == nullptr) {  // sent once by the valve: polled once or not at all
      slot.reset();
      if (reader.word(entry.second, key, {"once", "off"}) == "once") slot = request;
      continue;
    }
    const auto text = reader.scalar(entry.second, key);
    if (text == "off") {
      slot.reset();
      continue;
    }
    const auto tenths =
        text == "once" ? 0
                       : reader.integer(entry.second, key, 0, static_cast<long long>(resend->max));
    if (auto set = codec::set_field(request, "resend_tenths", std::int64_t{tenths}); !set) {
      reader.fail(entry.second, key, set.error().complaint);
    }
    slot = request;
  }
  std::vector<codec::ToValveMessage> out;
  for (const std::string_view name : names) {
    if (const auto it = schedule.find(name); it != schedule.end() && it->second) {
      out.push_back(*it->second);
    }
  }
  return out;
}

void read_gateway(const Reader& reader, const YAML::Node& g, GatewayConfig& config) {
  reader.expect_keys(g, "gateway",
                     {"name", "can", "domain", "profile", "offline_after_s", "stop_valves_on_exit",
                      "on_commander_lost", "allow_baud_change", "receive_coalesce_us",
                      "receive_coalesce_above_fps", "reject_unknown_serials", "record_frames"});
  if (g["name"]) config.bridge.gateway_name = reader.scalar(g["name"], "gateway.name");
  if (g["can"]) config.can = reader.scalar(g["can"], "gateway.can");
  if (g["domain"]) {
    config.domain =
        static_cast<int>(reader.integer(g["domain"], "gateway.domain", 0, dds::kMaxDomain));
  }
  if (g["profile"]) config.profile_file = reader.scalar(g["profile"], "gateway.profile");
  if (g["offline_after_s"]) {
    config.bridge.offline_after =
        seconds(reader.seconds(g["offline_after_s"], "gateway.offline_after_s", kMaxSeconds));
  }
  if (g["stop_valves_on_exit"]) {
    config.stop_valves_on_exit =
        reader.flag(g["stop_valves_on_exit"], "gateway.stop_valves_on_exit");
  }
  if (g["on_commander_lost"]) {
    config.on_commander_lost = reader.word(g["on_commander_lost"], "gateway.on_commander_lost",
                                           {"stop", "ignore"}) == "stop"
                                   ? OnCommanderLost::kStopItsValves
                                   : OnCommanderLost::kIgnore;
  }
  if (g["allow_baud_change"]) {
    config.bridge.allow_baud_change =
        reader.flag(g["allow_baud_change"], "gateway.allow_baud_change");
  }
  if (g["reject_unknown_serials"]) {
    config.bridge.reject_unknown_serials =
        reader.flag(g["reject_unknown_serials"], "gateway.reject_unknown_serials");
  }
  if (g["record_frames"]) {
    config.record_frames = reader.flag(g["record_frames"], "gateway.record_frames");
  }
  if (g["receive_coalesce_us"]) {
    config.receive_coalesce = std::chrono::microseconds(
        reader.integer(g["receive_coalesce_us"], "gateway.receive_coalesce_us", 0, 10'000));
  }
  if (g["receive_coalesce_above_fps"]) {
    config.receive_coalesce_above = static_cast<unsigned>(reader.integer(
        g["receive_coalesce_above_fps"], "gateway.receive_coalesce_above_fps", 0, 10'000));
  }
}

void read_commands(const Reader& reader, const YAML::Node& c, GatewayConfig& config) {
  reader.expect_keys(c, "commands",
                     {"completion_tolerance_deg", "reply_timeout_s", "move_margin_s", "assumed_dps",
                      "rate_per_valve", "burst_per_valve"});
  if (c["completion_tolerance_deg"]) {
    config.bridge.completion_tolerance_degrees =
        reader.number(c["completion_tolerance_deg"], "commands.completion_tolerance_deg", 0,
                      kMaxToleranceDegrees);
  }
  if (c["reply_timeout_s"]) {
    config.bridge.reply_timeout =
        seconds(reader.seconds(c["reply_timeout_s"], "commands.reply_timeout_s", kMaxSeconds));
  }
  if (c["move_margin_s"]) {
    config.bridge.move_margin =
        seconds(reader.seconds(c["move_margin_s"], "commands.move_margin_s", kMaxSeconds));
  }
  if (c["assumed_dps"]) {
    // The Degrees Per Second message's range; 0 would make every move's travel time infinite.
    config.bridge.assumed_dps =
        static_cast<unsigned>(reader.integer(c["assumed_dps"], "commands.assumed_dps", 1, 359));
  }
  // Above a bus's capacity (~2,000 frames/s at 250 kbit/s, ~8,000 at 1 Mbit/s) a limit limits
  // nothing; 0 turns it off.
  if (c["rate_per_valve"]) {
    config.bridge.command_rate_per_valve =
        reader.number(c["rate_per_valve"], "commands.rate_per_valve", 0, kMaxCommandRate);
  }
  if (c["burst_per_valve"]) {
    config.bridge.command_burst_per_valve = static_cast<unsigned>(
        reader.integer(c["burst_per_valve"], "commands.burst_per_valve", 1, kMaxCommandBurst));
  }
}

// The NAME's fields each by its ISO 11783-5 name, from the one table of them; the address is the
// sheet's 0xD5, so the NAME is never arbitrary-address capable.
void read_isobus(const Reader& reader, const YAML::Node& i, GatewayConfig& config) {
  constexpr std::string_view kFixed = "arbitrary_address_capable";
  std::vector<std::string_view> keys{"claim"};
  for (const auto& field : isobus::name_fields()) keys.push_back(field.name);
  if (i.IsMap() && i[std::string(kFixed)]) {
    reader.fail(i[std::string(kFixed)], "isobus.arbitrary_address_capable",
                "the gateway's address is the sheet's 0xD5, never another: its NAME is not "
                "arbitrary-address capable");
  }
  reader.expect_keys(i, "isobus", keys);
  auto& claim = config.bridge.isobus;
  if (i["claim"]) claim.claim = reader.flag(i["claim"], "isobus.claim");
  for (const auto& field : isobus::name_fields()) {
    const auto node = i[std::string(field.name)];
    if (!node || field.name == kFixed) continue;
    const std::string key = "isobus." + std::string(field.name);
    isobus::set_field(claim.name, field,
                      static_cast<std::uint32_t>(reader.integer(node, key, 0, field.max())));
  }
}

// A relative layout_file is beside the configuration that names it.
std::string beside(const std::string& source, const std::string& path) {
  const std::filesystem::path file(path);
  if (file.is_absolute()) return path;
  return (std::filesystem::path(source).parent_path() / file).lexically_normal().string();
}

void read_simulator(const Reader& reader, const YAML::Node& s, GatewayConfig& config) {
  reader.expect_keys(s, "simulator",
                     {"first_serial", "serials", "dps", "closed_deg", "opened_deg", "errors",
                      "churn_period_s", "churn_seed"});
  if (s["first_serial"]) {
    const auto serial =
        codec::parse_serial(reader.scalar(s["first_serial"], "simulator.first_serial"));
    if (!serial) reader.fail(s["first_serial"], "simulator.first_serial", serial.error().reason);
    config.sim_first_serial = *serial;
  }
  if (const auto serials = s["serials"]) {
    reader.expect_list(serials, "simulator.serials", "serials (TJV123456 or 123456)");
    if (s["first_serial"]) {
      reader.fail(serials, "simulator.serials", "give first_serial or serials, not both");
    }
    for (const auto& entry : serials) {
      const auto serial = codec::parse_serial(reader.scalar(entry, "simulator.serials"));
      if (!serial) reader.fail(entry, "simulator.serials", serial.error().reason);
      if (std::find(config.sim_serials.begin(), config.sim_serials.end(), *serial) !=
          config.sim_serials.end()) {
        reader.fail(entry, "simulator.serials", codec::format_serial(*serial) + " is listed twice");
      }
      config.sim_serials.push_back(*serial);
    }
  }
  // The simulator checks the combination (closed below opened, ...) when it starts.
  if (s["dps"]) {
    config.sim_degrees_per_second =
        reader.number(s["dps"], "simulator.dps", 1, field_of(codec::DegreesPerSecond{}, "dps").max);
  }
  if (s["closed_deg"]) {
    config.sim_closed_degrees =
        reader.number(s["closed_deg"], "simulator.closed_deg", 0, max_position_degrees());
  }
  if (s["opened_deg"]) {
    config.sim_opened_degrees =
        reader.number(s["opened_deg"], "simulator.opened_deg", 0, codec::kFullTurnOpenedDegrees);
  }
  if (const auto errors = s["errors"]) {
    reader.expect_list(errors, "simulator.errors", "errors (SERIAL:KIND:VALUE:LIMIT[:DIRECTION])");
    config.sim_errors.clear();
    for (const auto& entry : errors) {
      const auto error = sim::parse_error_spec(reader.scalar(entry, "simulator.errors"));
      if (!error) reader.fail(entry, "simulator.errors", error.error().reason);
      config.sim_errors.push_back(*error);
    }
  }
  if (s["churn_seed"]) {
    config.sim_churn_seed = static_cast<std::uint32_t>(
        reader.integer(s["churn_seed"], "simulator.churn_seed", 0, 4'294'967'295LL));
  }
  if (const auto period = s["churn_period_s"]) {
    const double value = reader.number(period, "simulator.churn_period_s", 0, kMaxSeconds);
    config.sim_churn_period =
        std::chrono::duration_cast<Duration>(std::chrono::duration<double>(value));
    // gateway: is read before simulator:, so offline_after is final here.
    if (config.sim_churn_period > Duration{0} &&
        config.sim_churn_period <= config.sim_churn_off_time()) {
      reader.fail(period, "simulator.churn_period_s",
                  "must be 0 (off) or longer than a churned valve stays off, "
                  "gateway.offline_after_s + 1 s = " +
                      format_seconds(config.sim_churn_off_time()) + " s");
    }
  }
}

}  // namespace

Result<GatewayConfig> parse_config(const std::string& text, const std::string& source,
                                   GatewayConfig base) {
  return yaml::parse<GatewayConfig>(
      source, text, [&](const Reader& reader, const YAML::Node& root) {
        if (root.IsNull()) return base;
        // Before the key check, which would call it unknown: it was a section until the layout.
        if (root.IsMap() && root["valves"]) {
          reader.fail(root["valves"], "valves",
                      "the mechanics of each valve are part of layout: now (docs/layout.md): "
                      "valves.default is layout.default, and a valve's go with its location");
        }
        reader.expect_keys(
            root, "the file",
            {"gateway", "commands", "poll", "layout", "layout_file", "simulator", "isobus"});
        if (const auto g = root["gateway"]) read_gateway(reader, g, base);
        if (const auto c = root["commands"]) read_commands(reader, c, base);
        if (const auto p = root["poll"]) base.bridge.poll = read_poll(reader, p);
        if (root["layout"] && root["layout_file"]) {
          reader.fail(root["layout_file"], "layout_file",
                      "the layout is in this file already (layout:); give one or the other");
        }
        if (const auto l = root["layout"]) {
          base.bridge.layout = layout::read_layout(reader, l, "layout");
          base.layout_in_config = true;
        }
        if (const auto f = root["layout_file"]) {
          base.layout_file = beside(source, reader.scalar(f, "layout_file"));
        }
        if (const auto s = root["simulator"]) read_simulator(reader, s, base);
        if (const auto i = root["isobus"]) read_isobus(reader, i, base);
        return base;
      });
}

Status read_layout_file(GatewayConfig& config) {
  if (config.layout_file.empty()) return {};
  if (config.layout_in_config) {
    return Error{ErrorCode::kInvalidValue,
                 "the layout is given twice: in the configuration (layout:) and as " +
                     config.layout_file + "; give one or the other"};
  }
  auto layout = layout::load_layout_file(config.layout_file);
  if (!layout) return layout.error();
  config.bridge.layout = std::move(layout).value();
  return {};
}

Result<GatewayConfig> load_config_file(const std::string& path, GatewayConfig base) {
  auto text = yaml::read_file(path);
  if (!text) return text.error();
  return parse_config(*text, path, std::move(base));
}

}  // namespace teejet::gateway
