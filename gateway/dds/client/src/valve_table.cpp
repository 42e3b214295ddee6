#include "teejet/client/valve_table.hpp"

#include <algorithm>

#include "teejet/client/names.hpp"

namespace teejet::client {

std::string reply_name(Telemetry telemetry) {
  switch (telemetry) {
    case TELEMETRY_VERSION:
      return "version";
    case TELEMETRY_POSITION:
      return "position";
    case TELEMETRY_TEMPERATURE:
      return "temperature";
    case TELEMETRY_VOLTAGE:
      return "voltage";
    case TELEMETRY_CURRENT:
      return "current";
    case TELEMETRY_DEGREES_PER_SECOND:
      return "degrees_per_second";
    case TELEMETRY_SPEED_DIRECTION:
      return "speed_direction";
    case TELEMETRY_RUN_TIME:
      return "run_time";
    case TELEMETRY_CYCLE_COUNTS:
      return "cycle_count";
  }
  return "unknown";
}

ValveTable::Entry& ValveTable::entry(std::uint32_t serial) {
  Entry& found = rows_[serial];
  found.row.serial = serial;
  return found;
}

void ValveTable::on_presence(const ValvePresence& presence) {
  Entry& found = entry(presence.serial());
  found.present = true;
  found.row.address = presence.address();
  found.row.online = presence.online();
  found.row.boot_mode = presence.boot_mode();
  found.row.gateway = presence.gateway().to_string();
}

void ValveTable::on_position(std::uint32_t serial, double degrees, std::uint64_t received_ns) {
  entry(serial).row.position_degrees = degrees;
  on_reply(serial, "position", {received_ns, {{"degrees", degrees}}});
}

void ValveTable::on_temperature(std::uint32_t serial, int valve_c, int sensor_c,
                                std::uint64_t received_ns) {
  entry(serial).row.temperature_c = valve_c;
  on_reply(serial, "temperature", {received_ns, {{"valve_c", valve_c}, {"sensor_c", sensor_c}}});
}

void ValveTable::on_voltage(std::uint32_t serial, double volts, std::uint64_t received_ns) {
  entry(serial).row.volts = volts;
  on_reply(serial, "voltage", {received_ns, {{"volts", volts}}});
}

void ValveTable::on_error(std::uint32_t serial, ErrorKind kind) {
  entry(serial).row.errors.insert(kind);
}

void ValveTable::on_error_cleared(std::uint32_t serial, ErrorKind kind) {
  entry(serial).row.errors.erase(kind);
}

void ValveTable::on_gateway_status(const GatewayStatus& status) {
  GatewaySummary& summary = gateways_[status.gateway().to_string()];
  summary.name = status.gateway().to_string();
  summary.can_interface = status.can_interface().to_string();
  summary.bus_state = status.bus_state();
  summary.valves_online = status.valves_online();
  summary.valves_known = status.valves_known();
  summary.frames_in = status.frames_in();
  summary.frames_out = status.frames_out();
  summary.decode_errors = status.decode_errors();
  summary.tx_errors = status.tx_errors();
  summary.rx_errors = status.rx_errors();
  summary.rx_dropped = status.rx_dropped();
}

void ValveTable::on_reply(std::uint32_t serial, const std::string& name, Reply reply) {
  replies_[{serial, name}] = std::move(reply);
}

std::vector<ValveRow> ValveTable::rows() const {
  std::vector<ValveRow> out;
  for (const auto& [serial, found] : rows_) {
    if (found.present) out.push_back(found.row);
  }
  return out;
}

std::optional<ValveRow> ValveTable::row(std::uint32_t serial) const {
  const auto it = rows_.find(serial);
  if (it == rows_.end() || !it->second.present) return std::nullopt;
  return it->second.row;
}

std::vector<GatewaySummary> ValveTable::gateways() const {
  std::vector<GatewaySummary> out;
  for (const auto& [name, summary] : gateways_) out.push_back(summary);
  return out;
}

std::optional<Reply> ValveTable::reply(std::uint32_t serial, const std::string& name) const {
  const auto it = replies_.find({serial, name});
  if (it == replies_.end()) return std::nullopt;
  return it->second;
}

std::size_t ValveTable::online_count() const {
  return static_cast<std::size_t>(std::count_if(rows_.begin(), rows_.end(), [](const auto& item) {
    return item.second.present && item.second.row.online;
  }));
}

bool ValveTable::directory_complete() const {
  if (gateways_.empty() || gateways_.size() < gateways_matched_) return false;
  for (const auto& [name, summary] : gateways_) {
    // Captured by name: clang before 16 cannot capture a structured binding.
    const auto known =
        std::count_if(rows_.begin(), rows_.end(), [&gateway = name](const auto& item) {
          return item.second.present && item.second.row.gateway == gateway;
        });
    if (static_cast<std::uint64_t>(known) < summary.valves_known) return false;
  }
  return true;
}

bool ValveTable::telemetry_complete() const {
  return std::all_of(rows_.begin(), rows_.end(), [](const auto& item) {
    const ValveRow& row = item.second.row;
    return !item.second.present || !row.online ||
           (row.position_degrees && row.temperature_c && row.volts);
  });
}

}  // namespace teejet::client
