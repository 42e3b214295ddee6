#include "teejet/client/json.hpp"

#include <string>

#include "teejet/codec/codec.hpp"
#include "teejet/dds/names.hpp"
#include "teejet/isobus/name.hpp"

namespace teejet::client {

nlohmann::json to_json(const codec::FieldValue& value) {
  return std::visit([](const auto& v) { return nlohmann::json(v); }, value);
}

std::optional<codec::FieldValue> field_value_of(const nlohmann::json& value) {
  if (value.is_number_unsigned()) {
    const auto number = value.get<std::uint64_t>();
    if (number > static_cast<std::uint64_t>(INT64_MAX)) return static_cast<double>(number);
    return static_cast<std::int64_t>(number);
  }
  if (value.is_number_integer()) return value.get<std::int64_t>();
  if (value.is_number_float()) return value.get<double>();
  if (value.is_string()) return value.get<std::string>();
  if (value.is_boolean()) return value.get<bool>();
  return std::nullopt;
}

nlohmann::json fields_json(const codec::FromValveMessage& message) {
  nlohmann::json fields = nlohmann::json::object();
  codec::for_each_field(message, [&](std::string_view name, const codec::FieldValue& value) {
    fields[std::string(name)] = to_json(value);
  });
  return fields;
}

nlohmann::json to_json(const ValveRow& row) {
  nlohmann::json errors = nlohmann::json::array();
  for (const ErrorKind kind : row.errors) errors.push_back(std::string(dds::to_string(kind)));
  nlohmann::json telemetry = nlohmann::json::object();
  for (const auto& [subject, reply] : row.telemetry)
    telemetry[subject] = fields_json(reply.message);
  const auto optional = [](const auto& value) -> nlohmann::json {
    if (!value) return nullptr;
    return *value;
  };
  return {
      {"serial", codec::format_serial(row.serial)},
      {"address", row.address},
      {"online", row.online && !row.gateway_lost},  // never online without a live gateway
      {"gateway_lost", row.gateway_lost},
      {"boot_mode", row.boot_mode},
      {"position", optional(row.position_degrees())},
      {"temperature_c", optional(row.temperature_c())},
      {"volts", optional(row.volts())},
      {"errors", errors},
      {"gateway", row.gateway},
      {"location", row.location},
      {"also_reported_by", row.also_reported_by},
      {"telemetry", telemetry},
  };
}

nlohmann::json to_json(const std::vector<ValveRow>& rows) {
  nlohmann::json array = nlohmann::json::array();
  for (const ValveRow& row : rows) array.push_back(to_json(row));
  return array;
}

nlohmann::json to_json(const LocationRow& place) {
  const auto optional = [](const std::optional<double>& value) -> nlohmann::json {
    if (!value) return nullptr;
    return *value;
  };
  return {
      {"order", place.order},
      {"location", place.name},
      {"role", dds::to_string(place.role)},
      {"serial", place.serial ? nlohmann::json(codec::format_serial(*place.serial)) : nullptr},
      {"state", place.gateway_lost ? "unknown" : dds::to_string(place.state)},
      {"gateway", place.gateway},
      {"closed_deg", optional(place.closed_degrees)},
      {"opened_deg", optional(place.opened_degrees)},
  };
}

nlohmann::json status_json(const CommandStatus& status) {
  return {
      {"event", "status"},
      {"serial", codec::format_serial(status.serial())},
      {"command_id", status.command_id()},
      {"origin", status.origin().to_string()},
      {"kind", dds::to_string(status.kind())},
      {"state", dds::to_string(status.state())},
      {"reason", status.reason().to_string()},
      {"stamp_ns", status.stamp_ns()},
  };
}

nlohmann::json status_json(const LayoutChangeStatus& status) {
  return {
      {"event", "layout_change"},
      {"location", status.location().to_string()},
      {"gateway", status.gateway().to_string()},
      {"kind", dds::to_string(status.kind())},
      {"state", dds::to_string(status.state())},
      {"serial", status.serial() != 0 ? nlohmann::json(codec::format_serial(status.serial()))
                                      : nlohmann::json(nullptr)},
      {"reason", status.reason().to_string()},
      {"change_id", status.change_id()},
      {"origin", status.origin().to_string()},
  };
}

nlohmann::json name_json(std::uint64_t value) {
  const isobus::Name name = isobus::from_value(value);
  nlohmann::json json{{"name", isobus::to_text(name)}};
  for (const auto& field : isobus::name_fields()) {
    json[std::string(field.name)] = isobus::field_value(name, field);
  }
  return json;
}

nlohmann::json claim_json(const GatewaySummary& gateway) {
  nlohmann::json neighbours = nlohmann::json::array();
  for (const BusNeighbour& neighbour : gateway.neighbours) {
    neighbours.push_back({{"address", codec::format_address(neighbour.address())},
                          {"name", name_json(neighbour.name())},
                          {"last_seen_ns", neighbour.last_seen_ns()}});
  }
  return {{"state", std::string(dds::to_string(gateway.address_claim))},
          {"address", codec::format_address(gateway.source_address)},
          {"name", name_json(gateway.isobus_name)},
          {"holder", gateway.address_claim == CLAIM_YIELDED ? name_json(gateway.address_holder)
                                                            : nlohmann::json(nullptr)},
          {"violations", gateway.address_violations},
          {"claims_in_valve_range", gateway.claims_in_valve_range},
          {"neighbours", std::move(neighbours)}};
}

}  // namespace teejet::client
