#pragma once

// What valvectl prints: the valve table for people, JSON for scripts, and one line per command
// status, position update or reply. Pure functions of the data, so the tests pin the format.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "teejet/client/json.hpp"
#include "teejet/client/valve_table.hpp"
#include "teejet/core/time.hpp"
#include "teejet/valve.h"

namespace teejet::valvectl {

using namespace client;

// An aligned text table with a header line; a missing value shows as "-". Below it, a warning
// line for each serial that more than one gateway reports online.
std::string render_table(const std::vector<ValveRow>& rows);
// The places of every gateway's layout in machine order: ORDER LOCATION ROLE SERIAL STATE POS_DEG
// ADDR GATEWAY, the position and address of the valve that sits there. Below it, a line for each
// name two gateways claim and for each online valve that sits in no place.
std::string render_layout(const ValveTable& table);
// {"locations":[{"order":1,"location":"left-master","role":"master","serial":"TJV000101",
//   "state":"ok","position":45.0,"address":216,"gateway":"...","closed_deg":0.0,
//   "opened_deg":360.0},...],"unassigned":["TJV000006"]}; missing values are null.
nlohmann::json layout_json(const ValveTable& table);
// One line per gateway: name, interface, bus state, valves online/known, frame counters, and
// its address claim ("holds 0xD5 as NAME 0x...", "GAVE UP 0xD5 to NAME 0x...: sends nothing").
std::string render_gateways(const std::vector<GatewaySummary>& gateways);
// The ECUs that claimed addresses on each gateway's bus: GATEWAY ADDR NAME INDUSTRY_GROUP
// DEVICE_CLASS FUNCTION MANUFACTURER IDENTITY LAST_SEEN, one row each; a NAME's fields from
// isobus::name_fields(). "no ECU has claimed an address on ..." for a gateway without any.
std::string render_neighbours(const std::vector<GatewaySummary>& gateways, Timestamp now);
// [{"gateway":"...","address_claim":{...client::claim_json...}}, ...]
nlohmann::json neighbours_json(const std::vector<GatewaySummary>& gateways);

// "TJV000002 target_degrees #17: ACCEPTED", "...: REJECTED: valve TJV000002 is offline".
std::string status_text(const CommandStatus& status);

// "section-03 on rig-1: APPLIED: TJV000007 sits there (TJV000003 left it)", "section-03 on
// rig-1: APPLIED: empty", "...: REJECTED: <reason>"; JSON {"event":"layout_change",
// "location":..,"gateway":..,"kind":"assign","state":"applied","serial":"TJV000007"|null,
// "reason":..,"change_id":..,"origin":..}.
std::string layout_change_text(const LayoutChangeStatus& status);

// "TJV000002 position 45.3"; {"event":"position","serial":"TJV000002","degrees":45.3}
std::string position_text(std::uint32_t serial, double degrees);
nlohmann::json position_json(std::uint32_t serial, double degrees);

// "TJV000006 voltage volts=12.0"; {"event":"reply","serial":..,"reply":"voltage","values":{..}}:
// the reply's subject and fields as the codec names them.
std::string reply_text(std::uint32_t serial, const Reply& reply);
nlohmann::json reply_json(std::uint32_t serial, const Reply& reply);

// One decimal, as the wire resolves degrees and volts: 45 -> "45.0".
std::string one_decimal(double value);

}  // namespace teejet::valvectl
