#include "page_command.hpp"

#include <algorithm>
#include <array>
#include <limits>
#include <set>

#include "teejet/client/command_check.hpp"
#include "teejet/client/json.hpp"
#include "teejet/codec/table.hpp"
#include "teejet/dds/conversions.hpp"
#include "token_guard.hpp"

namespace teejet::web {
namespace {

using nlohmann::json;

Error refused(std::string reason) { return Error{ErrorCode::kInvalidValue, std::move(reason)}; }

// The commands of the page, each a message of the sheet (stop_all: Stop to every online valve;
// request: a telemetry request by name). A command takes "serial" (but stop_all) and the
// message's fields by the codec's names, all required; besides them only "command", "id" and
// "token".
struct Shape {
  std::string_view name;
  std::optional<codec::ToValveMessage> message;  // nullopt: request
  bool every_online_valve = false;
};
const std::array<Shape, 7> kShapes{{
    {"move", codec::TargetDegrees{}},
    {"stop", codec::Stop{}},
    {"stop_all", codec::Stop{}, true},
    {"manual", codec::Manual{}},
    {"jog", codec::MillisecondsToRun{}},
    {"request", std::nullopt},
    {"clear_errors", codec::ClearErrors{}},
}};
constexpr const char* kReadOnly =
    "commands are disabled: teejet-web runs read-only (start it with --allow-commands)";
constexpr const char* kCommandNames =
    "move, stop, stop_all, manual, jog, request, clear_errors, assign, unassign";
// Layout changes: the fields each takes, and those it may leave out.
struct LayoutShape {
  std::string_view name;
  LayoutChangeKind kind;
  std::vector<std::string_view> fields;
  std::vector<std::string_view> optional_fields;
};
const std::array<LayoutShape, 2> kLayoutShapes{{
    {"assign", LAYOUT_ASSIGN, {"location", "serial"}, {"move"}},
    {"unassign", LAYOUT_UNASSIGN, {"location"}, {}},
}};

std::vector<std::string_view> fields_of(const Shape& shape) {
  std::vector<std::string_view> fields;
  if (!shape.every_online_valve) fields.push_back("serial");
  if (!shape.message) return {"serial", "telemetry", "resend_tenths"};
  for (const codec::FieldInfo& field : codec::describe(*shape.message).fields) {
    if (field.type != codec::FieldType::kMarker) fields.push_back(field.name);
  }
  return fields;
}

Result<std::uint32_t> in_table(std::uint32_t serial, const client::ValveTable& table) {
  if (!table.row(serial)) {
    return refused("unknown serial " + codec::format_serial(serial) + ": no gateway knows it");
  }
  return serial;
}

Result<std::uint32_t> known_serial(const json& value, const client::ValveTable& table) {
  if (!value.is_string()) return refused("serial must be a string like \"TJV000001\"");
  const auto text = value.get<std::string>();
  const auto serial = codec::parse_serial(text);
  if (!serial) return refused("invalid serial: " + serial.error().reason);
  return in_table(*serial, table);
}

// Whether `message` of command `name` has every `required` field and no field but those, the
// `optional` ones, "command", "id" and "token"; the refusal says which field.
Status known_fields(const std::string& name, const json& message,
                    const std::vector<std::string_view>& required,
                    const std::vector<std::string_view>& optional) {
  const auto among = [](const std::vector<std::string_view>& names, std::string_view key) {
    return std::find(names.begin(), names.end(), key) != names.end();
  };
  for (const auto& item : message.items()) {
    const std::string& key = item.key();
    if (key == "command" || key == "id" || key == "token") continue;
    if (!among(required, key) && !among(optional, key)) {
      return refused(name + ": unknown field \"" + key + "\"");
    }
  }
  for (const std::string_view field : required) {
    if (!message.contains(std::string(field))) {
      return refused(name + ": missing \"" + std::string(field) + "\"");
    }
  }
  return {};
}

// The one place called `value` among the gateways' layouts: two gateways claiming a name is a
// mistake of their layouts, and a change or command sent to either could be the wrong one.
Result<client::LocationRow> the_place(const json& value, const client::ValveTable& table) {
  if (!value.is_string()) return refused("location must be a string like \"section-01\"");
  const auto name = value.get<std::string>();
  const auto places = table.locations_named(name);
  if (places.empty())
    return refused("unknown location \"" + name + "\": no gateway's layout has it");
  if (places.size() > 1) {
    return refused("location \"" + name + "\" is in the layouts of " +
                   std::to_string(places.size()) + " gateways (" + client::gateway_names(places) +
                   "): a name belongs to one");
  }
  return places.front();
}

// The serial of the valve at place `value`.
Result<std::uint32_t> serial_at(const json& value, const client::ValveTable& table) {
  const auto place = the_place(value, table);
  if (!place) return place.error();
  if (!place->serial) {
    return refused("location \"" + place->name + "\" on " + place->gateway +
                   " is empty: no valve sits there");
  }
  if (!table.row(*place->serial)) {
    return refused("location \"" + place->name + "\" holds " +
                   codec::format_serial(*place->serial) + ", which no gateway knows");
  }
  return *place->serial;
}

// The message's fields from the page's values, refused as the codec refuses them.
Result<codec::ToValveMessage> with_page_fields(codec::ToValveMessage message, const json& page) {
  client::FieldValues values;
  for (const codec::FieldInfo& field : codec::describe(message).fields) {
    if (field.type == codec::FieldType::kMarker) continue;
    const json& given = page.at(std::string(field.name));
    const auto value = client::field_value_of(given);
    if (!value) {
      return refused(std::string(field.name) + " must be a number or a word, got " + given.dump());
    }
    values.emplace_back(field.name, *value);
  }
  auto built = client::with_fields(std::move(message), values);
  if (!built) return refused(built.error().field + " " + built.error().complaint);
  return built;
}

Result<codec::ToValveMessage> telemetry_request(const json& page) {
  const json& what = page.at("telemetry");
  const auto request =
      what.is_string() ? codec::telemetry_request(what.get<std::string>()) : std::nullopt;
  if (!request) {
    std::string names;
    for (const std::string_view name : codec::telemetry_names()) {
      if (!names.empty()) names += ' ';
      names += name;
    }
    return refused("telemetry " + what.dump() + " is not one of " + names);
  }
  if (codec::find_field(codec::describe(*request), "resend_tenths") != nullptr) {
    return with_page_fields(*request, page);
  }
  if (page.at("resend_tenths") != 0) {
    return refused("resend_tenths must be 0: a valve sends its " +
                   std::string(codec::subject(*request)) + " once");
  }
  return *request;
}

// The command for one valve command message, checked by the client's rules.
Result<ValveCommand> build(const Shape& shape, const json& page) {
  auto message = shape.message ? with_page_fields(*shape.message, page) : telemetry_request(page);
  if (!message) return message.error();
  auto command = client::checked_command(*message);
  if (!command) return refused(command.error().field + " " + command.error().complaint);
  return command;
}

// The message parsed (discarded when it is not JSON), or why it is not even read.
Result<json> read_message(std::string_view text) {
  if (text.size() > kMaxCommandBytes) {
    return refused("message of " + std::to_string(text.size()) + " bytes is over the limit of " +
                   std::to_string(kMaxCommandBytes));
  }
  if (!nested_within(text, kMaxJsonDepth)) {
    return refused("JSON nested deeper than " + std::to_string(kMaxJsonDepth) + " levels");
  }
  return json::parse(text, nullptr, /*allow_exceptions=*/false);
}

// The page's "id" when it is safe to send back, null otherwise.
json echoed_id(const Result<json>& message) {
  if (!message || !message->is_object() || !message->contains("id")) return nullptr;
  const json& id = message->at("id");
  if (id.is_number()) return id;
  if (id.is_string() && id.get_ref<const std::string&>().size() <= kMaxIdBytes) return id;
  return nullptr;
}

}  // namespace

bool nested_within(std::string_view text, int max_depth) {
  int depth = 0;
  bool in_string = false;
  bool escaped = false;
  for (const char c : text) {
    if (in_string) {
      if (escaped) {
        escaped = false;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > max_depth) return false;
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return true;
}

Result<PageCommand> parse_page_command(std::string_view text, const client::ValveTable& table) {
  const auto message = read_message(text);
  if (!message) return message.error();
  return check_page_command(*message, table);
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
  // A valve is named by its serial or by its place; "location" stands in for "serial".
  const bool by_location = !shape->every_online_valve && message.contains("location");
  if (by_location && message.contains("serial")) {
    return refused(name + ": name the valve by \"serial\" or by \"location\", not both");
  }
  auto fields = fields_of(*shape);
  if (by_location)
    std::replace(fields.begin(), fields.end(), std::string_view("serial"),
                 std::string_view("location"));
  if (const auto checked_fields = known_fields(name, message, fields, {}); !checked_fields) {
    return checked_fields.error();
  }

  PageCommand checked;
  if (shape->every_online_valve) {
    for (const client::ValveRow& row : table.rows()) {
      if (row.online) checked.serials.push_back(row.serial);
    }
    if (checked.serials.empty()) return refused("stop_all: no valve is online");
  } else {
    const auto serial = by_location ? serial_at(message.at("location"), table)
                                    : known_serial(message.at("serial"), table);
    if (!serial) return serial.error();
    checked.serials.push_back(*serial);
  }
  auto command = build(*shape, message);
  if (!command) return refused(name + ": " + command.error().reason);
  checked.command = std::move(*command);
  return checked;
}

Result<PageCommand> check_published_command(const ValveCommand& published,
                                            const client::ValveTable& table) {
  const auto serial = in_table(published.serial(), table);
  if (!serial) return serial.error();
  const auto message = dds::to_message(published);
  if (!message) return refused(message.error().reason);
  auto command = client::checked_command(*message);
  if (!command) return refused(command.error().field + " " + command.error().complaint);
  return PageCommand{{*serial}, std::move(*command)};
}

Result<PageLayoutChange> check_page_layout_change(const json& message,
                                                  const client::ValveTable& table) {
  if (!message.is_object() || !message.contains("command") || !message.at("command").is_string()) {
    return refused("a layout change must be a JSON object with \"command\"");
  }
  const auto name = message.at("command").get<std::string>();
  const auto shape = std::find_if(kLayoutShapes.begin(), kLayoutShapes.end(),
                                  [&](const LayoutShape& s) { return s.name == name; });
  if (shape == kLayoutShapes.end()) {
    return refused("unknown layout change \"" + name + "\": assign or unassign");
  }
  if (const auto checked_fields =
          known_fields(name, message, shape->fields, shape->optional_fields);
      !checked_fields) {
    return checked_fields.error();
  }
  const auto place = the_place(message.at("location"), table);
  if (!place) return refused(name + ": " + place.error().reason);
  std::uint32_t serial = 0;
  bool move = false;
  if (shape->kind == LAYOUT_ASSIGN) {
    const json& given = message.at("serial");
    if (!given.is_string()) return refused(name + ": serial must be a string like \"TJV000001\"");
    const auto parsed = codec::parse_serial(given.get<std::string>());
    if (!parsed) return refused(name + ": invalid serial: " + parsed.error().reason);
    serial = *parsed;
    if (message.contains("move")) {
      if (!message.at("move").is_boolean()) return refused(name + ": move must be true or false");
      move = message.at("move").get<bool>();
    }
  }
  return PageLayoutChange{client::layout_change_of(*place, shape->kind, serial, move),
                          place->participant};
}

namespace {

json field_json(const codec::FieldInfo& field) {
  json described{{"unit", field.unit}};
  switch (field.type) {
    case codec::FieldType::kNumber:
      described["type"] = "number";
      described["min"] = field.min;
      described["max"] = field.max;
      described["step"] = field.resolution;
      break;
    case codec::FieldType::kWord:
      described["type"] = "word";
      described["words"] = field.words;
      break;
    case codec::FieldType::kFlag:
      described["type"] = "flag";
      break;
    default:
      described["type"] = "text";
      break;
  }
  return described;
}

json fields_json(const codec::MessageInfo& message) {
  json fields = json::object();
  for (const codec::FieldInfo& field : message.fields) {
    if (field.type != codec::FieldType::kMarker)
      fields[std::string(field.name)] = field_json(field);
  }
  return fields;
}

}  // namespace

json page_protocol_json() {
  json commands = json::object();
  for (const Shape& shape : kShapes) {
    commands[std::string(shape.name)] =
        shape.message ? fields_json(codec::describe(*shape.message))
                      : json{{"telemetry", codec::telemetry_names()},
                             {"resend_tenths",
                              field_json(*codec::find_field(
                                  codec::describe(codec::RequestPosition{}), "resend_tenths"))}};
  }
  json telemetry = json::object();
  for (const codec::MessageInfo& message : codec::message_table(codec::Flow::kFromValve)) {
    if (!message.subject.empty()) telemetry[std::string(message.subject)] = fields_json(message);
  }
  return {{"commands", commands}, {"telemetry", telemetry}};
}

std::optional<std::string> policy_refusal(const CommandPolicy& policy,
                                          std::optional<std::string_view> token,
                                          const TokenCheck& check_token) {
  if (!policy.allow_commands) return kReadOnly;
  if (policy.token.empty()) return std::nullopt;
  constexpr const char* kWrongToken = "missing or wrong \"token\"";
  if (!token) return kWrongToken;
  if (check_token) return check_token(*token);
  if (!tokens_equal(*token, policy.token)) return kWrongToken;
  return std::nullopt;
}

json command_policy_json(const CommandPolicy& policy) {
  return {{"allowed", policy.allow_commands}, {"token_required", !policy.token.empty()}};
}

json handle_page_message(std::string_view text, const client::ValveTable& table,
                         const CommandPolicy& policy, CommandSender& sender,
                         const TokenCheck& check_token) {
  // Parsed once; the id is echoed even when the command is refused.
  const auto message = read_message(text);
  const json id = echoed_id(message);
  const auto refuse = [&](const std::string& reason) {
    return json{{"type", "refused"}, {"id", id}, {"reason", reason}};
  };
  if (!policy.allow_commands) return refuse(kReadOnly);
  if (!message) return refuse(message.error().reason);
  // What is not even an object is refused below for what it is; it can carry no command.
  if (message->is_object()) {
    std::optional<std::string_view> token;
    if (message->contains("token") && message->at("token").is_string()) {
      token = message->at("token").get_ref<const std::string&>();
    }
    if (const auto refusal = policy_refusal(policy, token, check_token)) return refuse(*refusal);
  }
  const bool layout_change =
      message->is_object() && message->contains("command") &&
      std::any_of(kLayoutShapes.begin(), kLayoutShapes.end(),
                  [&](const LayoutShape& shape) { return message->at("command") == shape.name; });
  if (layout_change) {
    const auto change = check_page_layout_change(*message, table);
    if (!change) return refuse(change.error().reason);
    json sent{{"location", change->change.location().to_string()},
              {"gateway", change->change.gateway().to_string()}};
    const auto change_id = sender.send(change->change, change->participant);
    if (change_id) {
      sent["change_id"] = *change_id;
    } else {
      sent["error"] = change_id.error().reason;
    }
    return json{{"type", "sent"}, {"id", id}, {"changes", json::array({sent})}};
  }
  const auto checked = check_page_command(*message, table);
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
