#include "teejet/client/json.hpp"

#include <cmath>
#include <string>

#include "teejet/codec/codec.hpp"
#include "teejet/dds/names.hpp"

namespace teejet::client {

double at_resolution(float value, int steps_per_unit) {
  // Dividing by the whole number of steps, not multiplying by the inexact 0.1, is what lands on
  // the double nearest to the decimal.
  return std::round(static_cast<double>(value) * steps_per_unit) / steps_per_unit;
}

nlohmann::json to_json(const ValveRow& row) {
  nlohmann::json errors = nlohmann::json::array();
  for (const ErrorKind kind : row.errors) errors.push_back(std::string(dds::to_string(kind)));
  const auto optional = [](const auto& value) -> nlohmann::json {
    if (!value) return nullptr;
    return *value;
  };
  return {
      {"serial", codec::format_serial(row.serial)},
      {"address", row.address},
      {"online", row.online},
      {"boot_mode", row.boot_mode},
      {"position", optional(row.position_degrees)},
      {"temperature_c", optional(row.temperature_c)},
      {"volts", optional(row.volts)},
      {"errors", errors},
      {"gateway", row.gateway},
  };
}

nlohmann::json to_json(const std::vector<ValveRow>& rows) {
  nlohmann::json array = nlohmann::json::array();
  for (const ValveRow& row : rows) array.push_back(to_json(row));
  return array;
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

}  // namespace teejet::client
