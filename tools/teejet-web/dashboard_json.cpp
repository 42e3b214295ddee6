#include "dashboard_json.hpp"

#include "teejet/client/json.hpp"
#include "teejet/codec/table.hpp"
#include "teejet/dds/names.hpp"

namespace teejet::web {
namespace {

nlohmann::json reply_value(const client::ValveRow& row, std::string_view subject,
                           std::string_view field) {
  const client::Reply* reply = row.reply(subject);
  const auto value = reply ? codec::field_value(reply->message, field) : std::nullopt;
  if (!value) return nullptr;
  return client::to_json(*value);
}

}  // namespace

nlohmann::json valve_json(const client::ValveRow& row, const Targets& targets) {
  nlohmann::json json = client::to_json(row);
  const auto target = targets.find(row.serial);
  json["target"] =
      target == targets.end() ? nlohmann::json(nullptr) : nlohmann::json(target->second);
  json["amps"] = reply_value(row, "current", "amps");
  json["speed_percent"] = reply_value(row, "speed_direction", "speed_percent");
  json["direction"] = reply_value(row, "speed_direction", "direction");
  return json;
}

nlohmann::json valves_json(const client::ValveTable& table, const Targets& targets) {
  nlohmann::json array = nlohmann::json::array();
  for (const client::ValveRow& row : table.rows()) array.push_back(valve_json(row, targets));
  return array;
}

nlohmann::json gateway_json(const client::GatewaySummary& gateway) {
  return {
      {"gateway", gateway.name},
      {"can_interface", gateway.can_interface},
      {"bus_state", std::string(dds::to_string(gateway.bus_state))},
      {"tx_errors", gateway.tx_errors},
      {"rx_errors", gateway.rx_errors},
      {"frames_in", gateway.frames_in},
      {"frames_out", gateway.frames_out},
      {"decode_errors", gateway.decode_errors},
      {"rx_dropped", gateway.rx_dropped},
      {"valves_online", gateway.valves_online},
      {"valves_known", gateway.valves_known},
      {"lost", gateway.lost},
      {"address_claim", client::claim_json(gateway)},
  };
}

DashboardFrame dashboard_frame(const client::ValveTable& table, const Targets& targets) {
  return dashboard_frame(table.rows(), table.gateways(), table.locations(), targets);
}

DashboardFrame dashboard_frame(const std::vector<client::ValveRow>& rows,
                               const std::vector<client::GatewaySummary>& gateways,
                               const std::vector<client::LocationRow>& places,
                               const Targets& targets) {
  DashboardFrame frame;
  for (const client::ValveRow& row : rows) {
    frame.valves.emplace_back(row.serial, valve_json(row, targets));
  }
  for (const client::GatewaySummary& gateway : gateways) {
    frame.gateways.emplace_back(gateway.name, gateway_json(gateway));
  }
  for (const client::LocationRow& place : places) {
    frame.places.emplace_back(place.gateway + "/" + place.name, client::to_json(place));
  }
  return frame;
}

std::set<std::uint32_t> retargeted(const Targets& before, const Targets& now) {
  std::set<std::uint32_t> serials;
  for (const auto& [serial, degrees] : now) {
    const auto it = before.find(serial);
    if (it == before.end() || it->second != degrees) serials.insert(serial);
  }
  for (const auto& [serial, degrees] : before) {
    if (!now.contains(serial)) serials.insert(serial);
  }
  return serials;
}

nlohmann::json UpdateBatcher::snapshot(const DashboardFrame& frame) {
  sent_valves_.clear();
  sent_gateways_.clear();
  sent_places_.clear();
  statuses_.clear();
  nlohmann::json valves = nlohmann::json::array();
  for (const auto& [serial, json] : frame.valves) valves.push_back(sent_valves_[serial] = json);
  nlohmann::json gateways = nlohmann::json::array();
  for (const auto& [name, json] : frame.gateways) gateways.push_back(sent_gateways_[name] = json);
  nlohmann::json places = nlohmann::json::array();
  for (const auto& [key, json] : frame.places) places.push_back(sent_places_[key] = json);
  return {{"type", "snapshot"}, {"valves", valves}, {"gateways", gateways}, {"places", places}};
}

void UpdateBatcher::add_status(const CommandStatus& status) {
  statuses_.push_back(client::status_json(status));
}

void UpdateBatcher::add_status(const LayoutChangeStatus& status) {
  statuses_.push_back(client::status_json(status));
}

std::optional<nlohmann::json> UpdateBatcher::tick(const DashboardFrame& frame,
                                                  std::uint64_t stamp_ms) {
  nlohmann::json valves = nlohmann::json::array();
  for (const auto& [serial, json] : frame.valves) {
    nlohmann::json& sent = sent_valves_[serial];
    if (json != sent) valves.push_back(sent = json);
  }
  nlohmann::json gateways = nlohmann::json::array();
  for (const auto& [name, json] : frame.gateways) {
    nlohmann::json& sent = sent_gateways_[name];
    if (json != sent) gateways.push_back(sent = json);
  }
  nlohmann::json places = nlohmann::json::array();
  for (const auto& [key, json] : frame.places) {
    nlohmann::json& sent = sent_places_[key];
    if (json != sent) places.push_back(sent = json);
  }
  if (valves.empty() && gateways.empty() && places.empty() && statuses_.empty()) {
    return std::nullopt;
  }
  nlohmann::json statuses(std::move(statuses_));
  statuses_.clear();
  return nlohmann::json{{"type", "update"},    {"tick", ++ticks_},     {"stamp_ms", stamp_ms},
                        {"valves", valves},    {"gateways", gateways}, {"places", places},
                        {"statuses", statuses}};
}

}  // namespace teejet::web
