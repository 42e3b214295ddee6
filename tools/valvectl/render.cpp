#include "render.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>

#include "teejet/client/json.hpp"
#include "teejet/codec/table.hpp"
#include "teejet/dds/names.hpp"
#include "teejet/isobus/name.hpp"

namespace teejet::valvectl {
namespace {

std::string address_text(std::uint8_t address) { return codec::format_address(address); }

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

namespace {

// "; holds 0xD5 as NAME 0x2008800000000000, 2 neighbour(s)" and the like.
std::string claim_text(const GatewaySummary& gateway) {
  const std::string address = address_text(gateway.source_address);
  const std::string name = isobus::to_text(isobus::from_value(gateway.isobus_name));
  std::string text;
  switch (gateway.address_claim) {
    case CLAIM_OFF:
      text = "; address claiming off";
      break;
    case CLAIM_CLAIMING:
      text = "; claiming " + address + " as NAME " + name;
      break;
    case CLAIM_CLAIMED:
      text = "; holds " + address + " as NAME " + name;
      break;
    case CLAIM_YIELDED:
      text = "; GAVE UP " + address + " to NAME " +
             isobus::to_text(isobus::from_value(gateway.address_holder)) +
             ": sends nothing, refuses commands";
      break;
  }
  if (!gateway.neighbours.empty()) {
    text += ", " + std::to_string(gateway.neighbours.size()) + " neighbour(s)";
  }
  if (gateway.address_violations > 0) {
    text += ", " + std::to_string(gateway.address_violations) + " address violation(s)";
  }
  if (gateway.claims_in_valve_range > 0) {
    text += ", " + std::to_string(gateway.claims_in_valve_range) + " claim(s) where valves live";
  }
  return text;
}

}  // namespace

std::string render_gateways(const std::vector<GatewaySummary>& gateways) {
  std::ostringstream out;
  for (const GatewaySummary& gateway : gateways) {
    out << "gateway " << gateway.name;
    if (!gateway.can_interface.empty()) out << " on " << gateway.can_interface;
    if (gateway.lost) out << ": LOST (no word from it: killed, powered off or cut off); last said";
    out << ": " << dds::to_string(gateway.bus_state) << ", " << gateway.valves_online << '/'
        << gateway.valves_known << " valves online, " << gateway.frames_in << " frames in, "
        << gateway.frames_out << " out, " << gateway.decode_errors << " decode errors"
        << claim_text(gateway) << '\n';
  }
  return out.str();
}

std::string render_neighbours(const std::vector<GatewaySummary>& gateways, Timestamp now) {
  const std::vector<Column> columns = {
      {"GATEWAY", kLeft},       {"ADDR", kLeft},          {"NAME", kLeft},
      {"INDUSTRY", kRight},     {"DEVICE_CLASS", kRight}, {"FUNCTION", kRight},
      {"MANUFACTURER", kRight}, {"IDENTITY", kRight},     {"LAST_SEEN", kRight},
  };
  const auto field = [](const isobus::Name& name, std::string_view key) {
    for (const auto& f : isobus::name_fields()) {
      if (f.name == key) return std::to_string(isobus::field_value(name, f));
    }
    return std::string("-");
  };
  std::vector<std::vector<std::string>> cells;
  std::ostringstream empty;
  for (const GatewaySummary& gateway : gateways) {
    if (gateway.neighbours.empty()) {
      empty << "no ECU has claimed an address on " << gateway.name
            << (gateway.can_interface.empty() ? "" : " (" + gateway.can_interface + ")") << '\n';
    }
    for (const BusNeighbour& neighbour : gateway.neighbours) {
      const isobus::Name name = isobus::from_value(neighbour.name());
      const auto age = now - from_unix_nanoseconds(neighbour.last_seen_ns());
      cells.push_back({gateway.name, address_text(neighbour.address()), isobus::to_text(name),
                       field(name, "industry_group"), field(name, "device_class"),
                       field(name, "function"), field(name, "manufacturer_code"),
                       field(name, "identity_number"),
                       std::to_string(std::max<long long>(
                           std::chrono::duration_cast<std::chrono::seconds>(age).count(), 0)) +
                           " s ago"});
    }
  }
  std::ostringstream out;
  if (!cells.empty()) out << aligned(columns, cells);
  out << empty.str();
  return out.str();
}

nlohmann::json neighbours_json(const std::vector<GatewaySummary>& gateways) {
  nlohmann::json list = nlohmann::json::array();
  for (const GatewaySummary& gateway : gateways) {
    list.push_back({{"gateway", gateway.name}, {"address_claim", claim_json(gateway)}});
  }
  return list;
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
