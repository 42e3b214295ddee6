#include "render.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
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

enum Align { kLeft, kRight };
struct Column {
  const char* header;
  Align align;
};

// A header line and one line per row, each column as wide as its widest cell, two blanks apart.
std::string aligned(const std::vector<Column>& columns,
                    const std::vector<std::vector<std::string>>& cells) {
  std::vector<std::size_t> widths;
  for (const Column& column : columns) widths.push_back(std::string(column.header).size());
  for (const auto& line : cells) {
    for (std::size_t i = 0; i < line.size(); ++i) widths[i] = std::max(widths[i], line[i].size());
  }
  std::ostringstream out;
  const auto append_line = [&](const std::vector<std::string>& line) {
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
  std::vector<std::string> header;
  for (const Column& column : columns) header.emplace_back(column.header);
  append_line(header);
  for (const auto& line : cells) append_line(line);
  return out.str();
}

// The valve at `place` when it is there to be seen: its gateway alive and the place ok.
std::optional<ValveRow> valve_at(const ValveTable& table, const LocationRow& place) {
  if (!place.serial || place.gateway_lost || place.state != LOCATION_OK) return std::nullopt;
  return table.row(*place.serial);
}

// Online valves that sit in no place, of gateways that have places.
std::vector<ValveRow> unassigned(const ValveTable& table) {
  std::set<std::string> with_places;
  for (const LocationRow& place : table.locations()) with_places.insert(place.gateway);
  std::vector<ValveRow> rows;
  for (const ValveRow& row : table.rows()) {
    if (row.online && !row.gateway_lost && row.location.empty() &&
        with_places.contains(row.gateway)) {
      rows.push_back(row);
    }
  }
  return rows;
}

}  // namespace

std::string one_decimal(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", value);
  return text;
}

std::string render_table(const std::vector<ValveRow>& rows) {
  const std::vector<Column> columns = {
      {"SERIAL", kLeft},   {"ADDR", kLeft},    {"ONLINE", kLeft},
      {"POS_DEG", kRight}, {"TEMP_C", kRight}, {"VOLTS", kRight},
      {"ERRORS", kLeft},   {"GATEWAY", kLeft}, {"LOCATION", kLeft},
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
        row.location.empty() ? "-" : row.location,
    });
  }
  std::ostringstream out;
  out << aligned(columns, cells);
  for (const ValveRow& row : rows) {
    if (row.also_reported_by.empty()) continue;
    out << "warning: " << codec::format_serial(row.serial) << " is online on " << row.gateway;
    for (const auto& other : row.also_reported_by) out << " and on " << other;
    out << ": two valves carry this serial, or something replays it; its gateways refuse "
           "commands to it but Stop until only one reports it\n";
  }
  return out.str();
}

std::string render_layout(const ValveTable& table) {
  const std::vector<Column> columns = {
      {"ORDER", kRight}, {"LOCATION", kLeft}, {"ROLE", kLeft}, {"SERIAL", kLeft},
      {"STATE", kLeft},  {"POS_DEG", kRight}, {"ADDR", kLeft}, {"GATEWAY", kLeft},
  };
  std::vector<std::vector<std::string>> cells;
  std::map<std::string, std::vector<std::string>> gateways_of;
  for (const LocationRow& place : table.locations()) {
    const auto valve = valve_at(table, place);
    cells.push_back({
        std::to_string(place.order),
        place.name,
        std::string(dds::to_string(place.role)),
        place.serial ? codec::format_serial(*place.serial) : "-",
        place.gateway_lost ? "unknown" : std::string(dds::to_string(place.state)),
        valve && valve->position_degrees() ? one_decimal(*valve->position_degrees()) : "-",
        valve ? address_text(valve->address) : "-",
        place.gateway,
    });
    gateways_of[place.name].push_back(place.gateway);
  }
  std::ostringstream out;
  out << aligned(columns, cells);
  for (const auto& [name, gateways] : gateways_of) {
    if (gateways.size() < 2) continue;
    out << "warning: " << name << " is a place in the layouts of";
    for (std::size_t i = 0; i < gateways.size(); ++i) {
      out << (i == 0 ? " " : i + 1 == gateways.size() ? " and " : ", ") << gateways[i];
    }
    out << ": one name for two places; rename one of them\n";
  }
  for (const ValveRow& row : unassigned(table)) {
    out << "unassigned: " << codec::format_serial(row.serial) << " at " << address_text(row.address)
        << " on " << row.gateway << " is online and sits in no place\n";
  }
  return out.str();
}

nlohmann::json layout_json(const ValveTable& table) {
  nlohmann::json places = nlohmann::json::array();
  for (const LocationRow& place : table.locations()) {
    const auto valve = valve_at(table, place);
    const auto position = valve ? valve->position_degrees() : std::nullopt;
    nlohmann::json row = to_json(place);
    row["position"] = position ? nlohmann::json(*position) : nullptr;
    row["address"] = valve ? nlohmann::json(valve->address) : nullptr;
    places.push_back(std::move(row));
  }
  nlohmann::json serials = nlohmann::json::array();
  for (const ValveRow& row : unassigned(table)) serials.push_back(codec::format_serial(row.serial));
  return {{"locations", places}, {"unassigned", serials}};
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

std::string layout_change_text(const LayoutChangeStatus& status) {
  std::string text = status.location().to_string() + " on " + status.gateway().to_string() + ": ";
  text += upper(std::string(dds::to_string(status.state())));
  const std::string reason = status.reason().to_string();
  if (status.state() != LAYOUT_CHANGE_APPLIED) return text + ": " + reason;
  text += status.serial() != 0 ? ": " + codec::format_serial(status.serial()) + " sits there"
                               : std::string(": empty");
  return reason.empty() ? text : text + " (" + reason + ")";
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
