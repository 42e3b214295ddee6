// docs/protocol.md's message tables are the codec's table, rendered: a message, a field, a range
// or a unit changed in the table changes the docs with it (TEEJET_UPDATE_DOCS=1 writes them).

#include <gtest/gtest.h>

#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <string>
#include <string_view>

#include "support/generated_section.hpp"
#include "teejet/codec/table.hpp"

namespace teejet::codec {
namespace {

std::string number(double value) {
  if (value == std::floor(value) && std::abs(value) < 1e15) {
    return std::to_string(static_cast<long long>(value));
  }
  std::array<char, 32> text{};
  const auto [end, ec] = std::to_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() ? std::string(text.data(), end) : "?";
}

std::string hex(std::uint32_t value) {
  std::array<char, 8> text{};
  std::snprintf(text.data(), text.size(), "0x%02X", value);
  return text.data();
}

// Concatenation without operator+ chains (gcc 12 warns falsely about them, -Wrestrict).
std::string cat(std::initializer_list<std::string_view> parts) {
  std::string text;
  for (const std::string_view part : parts) text.append(part);
  return text;
}

std::string field_text(const FieldInfo& field) {
  const std::string name = cat({"`", field.name, "`"});
  const std::string bytes =
      field.width == 1 ? "1 byte" : cat({std::to_string(field.width), " bytes"});
  switch (field.type) {
    case FieldType::kMarker:
      return cat({"marker `", hex(static_cast<std::uint32_t>(field.min)), "`"});
    case FieldType::kWord: {
      std::string words;
      for (const std::string_view word : field.words) {
        if (!words.empty()) words += ", ";
        words += word;
      }
      return cat({name, " ", words});
    }
    case FieldType::kSerial:
      return cat({name, " (", bytes, ") TJV and six digits"});
    case FieldType::kVersion:
      return cat({name, " (", bytes, ") major, minor, test character"});
    case FieldType::kFlag:
      return cat({name, " 0 or 1"});
    case FieldType::kNumber:
      break;
  }
  std::string text = cat({name, " (", bytes, ") "});
  if (!field.values.empty()) {
    for (std::size_t i = 0; i < field.values.size(); ++i) {
      text.append(i > 0 ? " or " : "").append(number(field.values[i]));
    }
  } else {
    text.append(number(field.min)).append("–").append(number(field.max));
  }
  // A unit that is a multiple ("0.1 s") reads as one: 0–255 × 0.1 s.
  if (!field.unit.empty()) {
    text.append(field.unit.front() >= '0' && field.unit.front() <= '9' ? " × " : " ")
        .append(field.unit);
  }
  if (field.resolution != 1.0) text.append(" by ").append(number(field.resolution));
  return text;
}

std::string fields_text(const MessageInfo& message) {
  std::string text;
  for (const FieldInfo& field : message.fields) {
    if (!text.empty()) text += "; ";
    text += field_text(field);
  }
  return text.empty() ? "–" : text;
}

std::string_view name_of(Flow flow, std::uint8_t id) {
  for (const MessageInfo& message : message_table(flow)) {
    if (message.id == id) return message.name;
  }
  return "?";
}

std::string to_valve_table() {
  std::string text =
      "| id | name | fields after the id | answered by | what it is |\n|---|---|---|---|---|\n";
  for (const MessageInfo& message : message_table(Flow::kToValve)) {
    const std::string answer =
        message.reply ? cat({"`", name_of(Flow::kFromValve, *message.reply), "`"}) : "";
    const std::string kind = message.run_command ? "run command"
                             : message.telemetry_request
                                 ? cat({"telemetry `", message.subject, "`"})
                                 : "setting";
    text += cat({"| `", hex(message.id), "` | `", message.name, "` | ", fields_text(message), " | ",
                 answer, " | ", kind, " |\n"});
  }
  return text;
}

std::string from_valve_table() {
  std::string text = "| id | name | fields after the id | what it is |\n|---|---|---|---|\n";
  for (const MessageInfo& message : message_table(Flow::kFromValve)) {
    const std::string kind = !message.subject.empty() ? cat({"reply `", message.subject, "`"})
                             : !message.error_kind.empty()
                                 ? cat({"error `", message.error_kind, "`"})
                                 : "announcement";
    text += cat({"| `", hex(message.id), "` | `", message.name, "` | ", fields_text(message), " | ",
                 kind, " |\n"});
  }
  return text;
}

TEST(DocsTables, ProtocolMdShowsTheCodecsTable) {
  const auto doc = std::filesystem::path(TEEJET_SOURCE_DIR) / "docs" / "protocol.md";
  teejet::testing::expect_generated_section(doc, "controller to valve", to_valve_table());
  teejet::testing::expect_generated_section(doc, "valve to controller", from_valve_table());
}

}  // namespace
}  // namespace teejet::codec
