#include "page_command.hpp"

#include <algorithm>
#include <array>
#include <limits>
#include <set>

#include "teejet/client/command_check.hpp"
#include "teejet/client/names.hpp"
#include "teejet/codec/codec.hpp"
#include "teejet/dds/conversions.hpp"

namespace teejet::web {
namespace {

using nlohmann::json;

Error refused(std::string reason) { return Error{ErrorCode::kInvalidValue, std::move(reason)}; }

// The fields each command takes, besides "command", "id" and "token"; all of them required.
struct Shape {
  std::string_view name;
  std::vector<std::string_view> fields;
};
const std::array<Shape, 7> kShapes{{
    {"move", {"serial", "degrees", "speed_percent", "direction"}},
    {"stop", {"serial"}},
    {"stop_all", {}},
    {"manual", {"serial", "speed_percent", "direction"}},
    {"jog", {"serial", "milliseconds", "speed_percent", "direction"}},
    {"request", {"serial", "telemetry", "resend_tenths"}},
    {"clear_errors", {"serial"}},
}};
constexpr const char* kReadOnly =
    "commands are disabled: teejet-web runs read-only (start it with --allow-commands)";
constexpr const char* kCommandNames = "move, stop, stop_all, manual, jog, request, clear_errors";

Result<std::uint32_t> known_serial(const json& value, const client::ValveTable& table) {
  if (!value.is_string()) return refused("serial must be a string like \"TJV000001\"");
  const auto text = value.get<std::string>();
  const auto serial = codec::parse_serial(text);
  if (!serial) return refused("invalid serial: " + serial.error().reason);
  if (!table.row(*serial)) {
    return refused("unknown serial " + codec::format_serial(*serial) + ": no gateway knows it");
  }
  return *serial;
}

// A whole number for the codec to check against its range; the codec takes unsigned.
Result<unsigned> whole_number(const json& message, const char* field) {
  const json& value = message.at(field);
  if (!value.is_number_integer() || value.is_number_float()) {
    return refused(std::string(field) + " must be a whole number, got " + value.dump());
  }
  if (!value.is_number_unsigned() ||
      value.get<std::uint64_t>() > std::numeric_limits<unsigned>::max()) {
    return refused(std::string(field) + " " + value.dump() + " is out of range");
  }
  return value.get<unsigned>();
}

Result<Direction> direction_of(const json& message, bool allow_shortest) {
  const json& value = message.at("direction");
  const char* allowed = allow_shortest ? "open, close or shortest" : "open or close";
  if (!value.is_string()) return refused(std::string("direction must be ") + allowed);
  const auto direction = client::parse_direction(value.get<std::string>(), allow_shortest);
  if (!direction)
    return refused("direction \"" + value.get<std::string>() + "\" is not " + allowed);
  return *direction;
}

// The command for one valve command message, checked by the client's rules.
Result<ValveCommand> build(std::string_view name, const json& message) {
  const auto speed = [&]() { return whole_number(message, "speed_percent"); };
  if (name == "move") {
    if (!message.at("degrees").is_number()) return refused("degrees must be a number");
    auto s = speed();
    if (!s) return s.error();
    auto d = direction_of(message, /*allow_shortest=*/true);
    if (!d) return d.error();
    return client::checked_command(codec::TargetDegrees{*s, client::target_direction(*d),
                                                          message.at("degrees").get<double>()});
  }
  if (name == "stop" || name == "stop_all") return client::checked_command(codec::Stop{});
  if (name == "clear_errors") return client::checked_command(codec::ClearErrors{});
  if (name == "manual" || name == "jog") {
    auto s = speed();
    if (!s) return s.error();
    auto d = direction_of(message, /*allow_shortest=*/false);
    if (!d) return d.error();
    if (name == "manual") {
      return client::checked_command(codec::Manual{*s, client::drive_direction(*d)});
    }
    auto ms = whole_number(message, "milliseconds");
    if (!ms) return ms.error();
    return client::checked_command(
        codec::MillisecondsToRun{*s, client::drive_direction(*d), *ms});
  }
  // request
  const json& what = message.at("telemetry");
  const auto telemetry =
      what.is_string() ? client::parse_telemetry(what.get<std::string>()) : std::nullopt;
  if (!telemetry) {
    return refused("telemetry " + what.dump() +
                   " is not one of version position temperature voltage current dps speed "
                   "run-time cycle-counts");
  }
  auto resend = whole_number(message, "resend_tenths");
  if (!resend) return resend.error();
  if (*resend > std::numeric_limits<std::uint8_t>::max()) {
    // Checked here only because the IDL's uint8 would wrap it before the codec sees it.
    return refused("resend_tenths " + std::to_string(*resend) + " is outside 0 to 255");
  }
  ValveCommand asked;
  asked.kind(COMMAND_REQUEST);
  asked.telemetry(*telemetry);
  asked.resend_tenths(static_cast<std::uint8_t>(*resend));
  const auto request = dds::to_message(asked);
  if (!request) {
    // The contract names the command kind first, as parse_page_command() does: say it once.
    return refused(client::without_leading_name(request.error().reason));
  }
  return client::checked_command(*request);
}

}  // namespace

Result<PageCommand> parse_page_command(std::string_view text, const client::ValveTable& table) {
  if (text.size() > kMaxCommandBytes) {
    return refused("message of " + std::to_string(text.size()) + " bytes is over the limit of " +
                   std::to_string(kMaxCommandBytes));
  }
  return check_page_command(json::parse(text, nullptr, /*allow_exceptions=*/false), table);
}

Result<PageCommand> check_page_command(const json& message, const client::ValveTable& table) {
  if (message.is_discarded()) return refused("malformed JSON");
  if (!message.is_object()) return refused("a command must be a JSON object");
  if (!message.contains("command") || !message.at("command").is_string()) {
    return refused("missing \"command\": one of " + std::string(kCommandNames));
  }
  const auto name = message.at("command").get<std::string>();
  const auto shape =
      std::find_if(kShapes.begin(), kShapes.end(), [&](const Shape& s) { return s.name == name; });
  if (shape == kShapes.end()) {
    return refused("unknown command \"" + name + "\": one of " + kCommandNames);
  }
  for (const auto& [key, value] : message.items()) {
    if (key == "command" || key == "id" || key == "token") continue;
    if (std::find(shape->fields.begin(), shape->fields.end(), key) == shape->fields.end()) {
      return refused(name + ": unknown field \"" + key + "\"");
    }
  }
  for (const std::string_view field : shape->fields) {
    if (!message.contains(std::string(field))) {
      return refused(name + ": missing \"" + std::string(field) + "\"");
    }
  }

  PageCommand checked;
  if (name == "stop_all") {
    for (const client::ValveRow& row : table.rows()) {
      if (row.online) checked.serials.push_back(row.serial);
    }
    if (checked.serials.empty()) return refused("stop_all: no valve is online");
  } else {
    const auto serial = known_serial(message.at("serial"), table);
    if (!serial) return serial.error();
    checked.serials.push_back(*serial);
  }
  auto command = build(name, message);
  if (!command) return refused(name + ": " + command.error().reason);
  checked.command = std::move(*command);
  return checked;
}

json command_policy_json(const CommandPolicy& policy) {
  return {{"allowed", policy.allow_commands}, {"token_required", !policy.token.empty()}};
}

json handle_page_message(std::string_view text, const client::ValveTable& table,
                         const CommandPolicy& policy, CommandSender& sender) {
  json id = nullptr;
  const auto refuse = [&](const std::string& reason) {
    return json{{"type", "refused"}, {"id", id}, {"reason", reason}};
  };
  // Parsed once, unless it is too long to read at all; the id is echoed even when the command
  // is refused, as long as the message could be read.
  const bool readable = text.size() <= kMaxCommandBytes;
  const json message = readable ? json::parse(text, nullptr, /*allow_exceptions=*/false)
                                : json(json::value_t::discarded);
  if (message.is_object() && message.contains("id")) id = message.at("id");
  if (!policy.allow_commands) return refuse(kReadOnly);
  // What is not even an object is refused below for what it is; it can carry no command.
  if (!policy.token.empty() && message.is_object()) {
    const bool match = message.contains("token") && message.at("token").is_string() &&
                       message.at("token").get<std::string>() == policy.token;
    if (!match) return refuse("missing or wrong \"token\"");
  }
  const auto checked =
      readable ? check_page_command(message, table) : parse_page_command(text, table);
  if (!checked) return refuse(checked.error().reason);
  json commands = json::array();
  for (const std::uint32_t serial : checked->serials) {
    ValveCommand command = checked->command;
    command.serial(serial);
    const auto command_id = sender.send(command);
    json sent{{"serial", codec::format_serial(serial)}};
    if (command_id) {
      sent["command_id"] = *command_id;
    } else {
      sent["error"] = command_id.error().reason;
    }
    commands.push_back(std::move(sent));
  }
  return json{{"type", "sent"}, {"id", id}, {"commands", commands}};
}

}  // namespace teejet::web
