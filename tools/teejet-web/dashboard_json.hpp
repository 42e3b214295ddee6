#pragma once

// The JSON teejet-web sends: the valve table (GET /api/valves and the page's first message),
// gateway health, and one batched update per tick. Pure functions of the client's ValveTable, so
// the page shows exactly what `valvectl list` and `watch` would, and the tests pin the format.
// docs/web.md describes every message.

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "target_tracker.hpp"
#include "teejet/client/valve_table.hpp"
#include "teejet/valve.h"

namespace teejet::web {

// The client's row (serial, address, online, boot_mode, position, temperature_c, volts, errors,
// gateway, telemetry) with what the dashboard adds: "target" of the running command, "amps" and
// "speed_percent"/"direction" from the latest current and speed replies; null when unknown.
nlohmann::json valve_json(const client::ValveRow& row, const Targets& targets);
// Every valve, by serial: the body of GET /api/valves.
nlohmann::json valves_json(const client::ValveTable& table, const Targets& targets);

// {"gateway":"bench","can_interface":"can0","bus_state":"error_active","tx_errors":0,
//  "rx_errors":0,"frames_in":10,"frames_out":4,"decode_errors":0,"rx_dropped":0,
//  "valves_online":4,"valves_known":4}
nlohmann::json gateway_json(const client::GatewaySummary& gateway);

// Valves' and every gateway's and place's JSON at one instant, in the table's order: made once
// per tick and compared by each page's batcher, so that more pages do not mean more JSON to
// build. A page's first frame holds every valve; a tick's only those that changed since the last
// tick (client::ValveView::changes_since) or whose target did.
struct DashboardFrame {
  std::vector<std::pair<std::uint32_t, nlohmann::json>> valves;
  std::vector<std::pair<std::string, nlohmann::json>> gateways;
  // Every place of every gateway's layout (client::to_json(LocationRow)), keyed
  // "gateway/location", in machine order.
  std::vector<std::pair<std::string, nlohmann::json>> places;
};
DashboardFrame dashboard_frame(const client::ValveTable& table, const Targets& targets);
DashboardFrame dashboard_frame(const std::vector<client::ValveRow>& rows,
                               const std::vector<client::GatewaySummary>& gateways,
                               const std::vector<client::LocationRow>& places,
                               const Targets& targets);
// The serials whose target is new, changed or gone between `before` and `now`.
std::set<std::uint32_t> retargeted(const Targets& before, const Targets& now);

// Collects what changed between ticks and makes one message of it, so that the page gets 20-30
// messages a second however many samples arrive. A tick compares each valve's and gateway's JSON
// with what the page was last sent: a valve that moved twice between ticks is sent once, with
// its latest state. Command statuses are events, not state: every one is kept until the tick.
class UpdateBatcher {
 public:
  // The first message of a page: {"type":"snapshot","valves":[...],"gateways":[...],
  // "places":[...]}. What it holds counts as sent, so the next tick only carries changes.
  nlohmann::json snapshot(const DashboardFrame& frame);

  void add_status(const CommandStatus& status);
  void add_status(const LayoutChangeStatus& status);  // "event":"layout_change" in "statuses"

  // {"type":"update","tick":N,"stamp_ms":..,"valves":[changed],"gateways":[changed],
  //  "places":[changed],"statuses":[since the last tick]}, or nullopt when nothing changed
  //  (nothing to send).
  // `stamp_ms` is the caller's clock, so that the page can plot against it.
  std::optional<nlohmann::json> tick(const DashboardFrame& frame, std::uint64_t stamp_ms);

 private:
  std::map<std::uint32_t, nlohmann::json> sent_valves_;
  std::map<std::string, nlohmann::json> sent_gateways_;
  std::map<std::string, nlohmann::json> sent_places_;
  std::vector<nlohmann::json> statuses_;
  std::uint64_t ticks_ = 0;
};

}  // namespace teejet::web
