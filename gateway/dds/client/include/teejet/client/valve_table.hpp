#pragma once

// The latest known state of every valve and gateway on a domain, as valvectl shows it. Pure
// data: ValveView fills it from DDS samples, the renderers and the tests read it.

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "teejet/valve.h"

namespace teejet::client {

// One line of `valvectl list`.
struct ValveRow {
  std::uint32_t serial = 0;
  std::uint8_t address = 0;
  bool online = false;
  bool boot_mode = false;
  std::string gateway;
  std::optional<double> position_degrees;
  std::optional<int> temperature_c;  // the valve's own, not its angle sensor's
  std::optional<double> volts;
  std::set<ErrorKind> errors;  // latched, until Clear Errors disposes them
};

struct GatewaySummary {
  std::string name;
  std::string can_interface;
  BusState bus_state = BUS_ERROR_ACTIVE;
  std::uint32_t valves_online = 0;
  std::uint32_t valves_known = 0;
  std::uint64_t frames_in = 0;
  std::uint64_t frames_out = 0;
  std::uint64_t decode_errors = 0;
  std::uint16_t tx_errors = 0;  // the CAN controller's error counters
  std::uint16_t rx_errors = 0;
  std::uint64_t rx_dropped = 0;
};

// A valve's answer to a request, as named fields in engineering units.
struct Reply {
  std::uint64_t received_ns = 0;
  nlohmann::json values;  // e.g. {"volts": 12.1}
};

// The topic-level name of what a reply carries: "position", "baud_rate", ...; one per
// telemetry type, so `request` can wait for the answer to what it asked.
std::string reply_name(Telemetry telemetry);
inline constexpr const char* kBaudRateReply = "baud_rate";

class ValveTable {
 public:
  void on_presence(const ValvePresence& presence);
  void on_position(std::uint32_t serial, double degrees, std::uint64_t received_ns);
  void on_temperature(std::uint32_t serial, int valve_c, int sensor_c, std::uint64_t received_ns);
  void on_voltage(std::uint32_t serial, double volts, std::uint64_t received_ns);
  void on_error(std::uint32_t serial, ErrorKind kind);
  void on_error_cleared(std::uint32_t serial, ErrorKind kind);
  void on_gateway_status(const GatewayStatus& status);
  // Any other telemetry: kept only as the latest reply of its kind.
  void on_reply(std::uint32_t serial, const std::string& name, Reply reply);

  // Valves with a presence sample, by serial.
  std::vector<ValveRow> rows() const;
  std::optional<ValveRow> row(std::uint32_t serial) const;
  std::vector<GatewaySummary> gateways() const;  // by name
  std::optional<Reply> reply(std::uint32_t serial, const std::string& name) const;
  std::size_t online_count() const;

  // How many gateways discovery has found so far (writers of gateway status matched).
  void set_gateways_matched(std::size_t count) { gateways_matched_ = count; }

  // Whether the directory is all here: every gateway found (at least one) has reported its
  // status, and each has published presence for as many valves as it says it knows. Presence
  // and gateway status are durable, so this holds shortly after discovery.
  bool directory_complete() const;
  // Whether every online valve has reported position, temperature and voltage.
  bool telemetry_complete() const;
  bool empty() const { return rows_.empty() && gateways_.empty(); }

 private:
  // Telemetry may arrive before presence; such a row stays hidden until presence arrives.
  struct Entry {
    ValveRow row;
    bool present = false;
  };
  Entry& entry(std::uint32_t serial);

  std::map<std::uint32_t, Entry> rows_;
  std::map<std::string, GatewaySummary> gateways_;
  std::map<std::pair<std::uint32_t, std::string>, Reply> replies_;
  std::size_t gateways_matched_ = 0;
};

}  // namespace teejet::client
