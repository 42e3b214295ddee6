#include "render.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "teejet/codec/table.hpp"
#include "teejet/dds/names.hpp"

namespace teejet::valvectl {
namespace {

std::string address_text(std::uint8_t address) {
  char text[8];
  std::snprintf(text, sizeof text, "0x%02X", address);
  return text;
}

std::string errors_text(const std::set<ErrorKind>& errors) {
  if (errors.empty()) return "-";
  std::string text;
  for (const ErrorKind kind : errors) {
    if (!text.empty()) text += ',';
    text += dds::to_string(kind);
  }
  return text;
}

std::string upper(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  return text;
}

// Strings bare, numbers as JSON writes them (values are already rounded to their resolution).
std::string scalar_text(const nlohmann::json& value) {
  if (value.is_string()) return value.get<std::string>();
  return value.dump();
}

}  // namespace

std::string one_decimal(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", value);
  return text;
}

std::string render_table(const std::vector<ValveRow>& rows) {
  enum Align { kLeft, kRight };
  struct Column {
    const char* header;
    Align align;
  };
  const std::vector<Column> columns = {
      {"SERIAL", kLeft},  {"ADDR", kLeft},   {"ONLINE", kLeft}, {"POS_DEG", kRight},
      {"TEMP_C", kRight}, {"VOLTS", kRight}, {"ERRORS", kLeft}, {"GATEWAY", kLeft},
  };
  std::vector<std::vector<std::string>> cells;
  for (const ValveRow& row : rows) {
    cells.push_back({
        codec::format_serial(row.serial),
        address_text(row.address),
        row.gateway_lost ? "unknown" : (row.boot_mode ? "boot" : (row.online ? "yes" : "no")),
        row.position_degrees() ? one_decimal(*row.position_degrees()) : "-",
        row.temperature_c() ? std::to_string(*row.temperature_c()) : "-",
        row.volts() ? one_decimal(*row.volts()) : "-",
        errors_text(row.errors),
        row.gateway,
    });
  }
  std::vector<std::size_t> widths;
  for (const Column& column : columns) widths.push_back(std::string(column.header).size());
  for (const auto& line : cells) {
    for (std::size_t i = 0; i < line.size(); ++i) widths[i] = std::max(widths[i], line[i].size());
  }
  const auto append_line = [&](std::ostringstream& out, const std::vector<std::string>& line) {
    std::string text;
    for (std::size_t i = 0; i < line.size(); ++i) {
      const std::string padding(widths[i] - line[i].size(), ' ');
      text += columns[i].align == kRight ? padding + line[i] : line[i] + padding;
      if (i + 1 < line.size()) text += "  ";
    }
    // The last column is left-aligned: no trailing blanks.
    text.erase(text.find_last_not_of(' ') + 1);
    out << text << '\n';
  };
  std::ostringstream out;
  std::vector<std::string> header;
  for (const Column& column : columns) header.emplace_back(column.header);
  append_line(out, header);
  for (const auto& line : cells) append_line(out, line);
  for (const ValveRow& row : rows) {
    if (row.also_reported_by.empty()) continue;
    out << "warning: " << codec::format_serial(row.serial) << " is online on " << row.gateway;
    for (const auto& other : row.also_reported_by) out << " and on " << other;
    out << ": two valves carry this serial, or something replays it; its gateways refuse "
           "commands to it but Stop until only one reports it\n";
  }
  return out.str();
}

std::string render_gateways(const std::vector<GatewaySummary>& gateways) {
  std::ostringstream out;
  for (const GatewaySummary& gateway : gateways) {
    out << "gateway " << gateway.name;
    if (!gateway.can_interface.empty()) out << " on " << gateway.can_interface;
    if (gateway.lost) out << ": LOST (no word from it: killed, powered off or cut off); last said";
    out << ": " << dds::to_string(gateway.bus_state) << ", " << gateway.valves_online << '/'
        << gateway.valves_known << " valves online, " << gateway.frames_in << " frames in, "
        << gateway.frames_out << " out, " << gateway.decode_errors << " decode errors\n";
  }
  return out.str();
}

std::string status_text(const CommandStatus& status) {
  std::string text = codec::format_serial(status.serial()) + ' ';
  text += dds::to_string(status.kind());
  text += " #" + std::to_string(status.command_id()) + ": ";
  text += upper(std::string(dds::to_string(status.state())));
  if (status.reason().size() > 0) text += ": " + status.reason().to_string();
  return text;
}

std::string position_text(std::uint32_t serial, double degrees) {
  return codec::format_serial(serial) + " position " + one_decimal(degrees);
}

nlohmann::json position_json(std::uint32_t serial, double degrees) {
  return {{"event", "position"}, {"serial", codec::format_serial(serial)}, {"degrees", degrees}};
}

std::string reply_text(std::uint32_t serial, const Reply& reply) {
  std::string text =
      codec::format_serial(serial) + ' ' + std::string(codec::subject(reply.message));
  codec::for_each_field(reply.message, [&](std::string_view field, const codec::FieldValue& value) {
    text += ' ' + std::string(field) + '=' + scalar_text(to_json(value));
  });
  return text;
}

nlohmann::json reply_json(std::uint32_t serial, const Reply& reply) {
  return {{"event", "reply"},
          {"serial", codec::format_serial(serial)},
          {"reply", codec::subject(reply.message)},
          {"values", fields_json(reply.message)},
          {"received_ns", reply.received_ns}};
}

}  // namespace teejet::valvectl
