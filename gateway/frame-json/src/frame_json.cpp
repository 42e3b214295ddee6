#include "teejet/frame_json/frame_json.hpp"

#include <array>
#include <cstdio>
#include <variant>

namespace teejet::frame_json {
namespace {

using nlohmann::ordered_json;

constexpr std::uint32_t kMicrosecondsPerSecond = 1'000'000;

// Log lines and a few decoded strings (a version's test character) are raw bytes from the bus
// or the file; replacing invalid UTF-8 keeps one bad byte from aborting the whole run.
std::string dump(const ordered_json& json) {
  return json.dump(-1, ' ', false, ordered_json::error_handler_t::replace);
}

ordered_json fields_json(const codec::AnyMessage& message) {
  auto fields = ordered_json::object();
  std::visit(
      [&fields](const auto& directional) {
        codec::for_each_field(
            directional, [&fields](std::string_view name, const codec::FieldValue& value) {
              fields[std::string(name)] =
                  std::visit([](const auto& v) { return ordered_json(v); }, value);
            });
      },
      message);
  return fields;
}

}  // namespace

ordered_json frame_object(const codec::DecodedFrame& frame) {
  ordered_json json;
  json["dir"] = codec::to_string(frame.route.flow);
  json["addr"] = frame.route.valve_address;
  json["msg"] = std::visit(
      [](const auto& directional) { return std::string(codec::message_name(directional)); },
      frame.message);
  json["fields"] = fields_json(frame.message);
  return json;
}

std::string timestamp_json_number(std::uint64_t seconds, std::uint32_t microseconds) {
  seconds += microseconds / kMicrosecondsPerSecond;
  microseconds %= kMicrosecondsPerSecond;
  std::array<char, 32> text{};
  std::snprintf(text.data(), text.size(), "%llu.%06u", static_cast<unsigned long long>(seconds),
                microseconds);
  return text.data();
}

std::string record_json_line(const candump::LogRecord& record, const codec::DecodedFrame& frame,
                             std::optional<std::string_view> gateway) {
  ordered_json members;
  if (gateway) members["gw"] = *gateway;
  members["iface"] = record.interface_name;
  const auto frame_members = frame_object(frame);
  for (const auto& member : frame_members.items()) members[member.key()] = member.value();
  // nlohmann cannot embed preformatted number text, so "t" is spliced in front of the rest.
  return "{\"t\":" + timestamp_json_number(record.seconds, record.microseconds) + "," +
         dump(members).substr(1);
}

std::string error_json_line(std::string_view reason, std::string_view line,
                            std::optional<std::string_view> gateway) {
  ordered_json json;
  json["error"] = reason;
  if (gateway) json["gw"] = *gateway;
  json["line"] = line;
  return dump(json);
}

std::string decode_record(const candump::LogRecord& record,
                          std::optional<std::string_view> gateway) {
  const auto decoded = codec::decode(record.frame);
  if (decoded) return record_json_line(record, *decoded, gateway);
  return error_json_line(decoded.error().reason,
                         candump::format_log_line(record.seconds, record.microseconds,
                                                  record.interface_name, record.frame),
                         gateway);
}

std::string message_error_json_line(std::string_view reason, std::string_view topic,
                                    std::uint32_t sequence, std::uint64_t log_time) {
  ordered_json json;
  json["error"] = reason;
  json["topic"] = topic;
  json["sequence"] = sequence;
  json["log_time"] = log_time;
  return dump(json);
}

std::string decode_log_line(std::string_view line) {
  const auto record = candump::parse_log_line(line);
  if (!record) return error_json_line(record.error().reason, line);
  const auto decoded = codec::decode(record->frame);
  if (!decoded) return error_json_line(decoded.error().reason, line);
  return record_json_line(*record, *decoded);
}

bool is_blank_line(std::string_view line) {
  return line.find_first_not_of(" \t\r") == std::string_view::npos;
}

}  // namespace teejet::frame_json
