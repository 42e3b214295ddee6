#pragma once

// What valvectl prints: the valve table for people, JSON for scripts, and one line per command
// status, position update or reply. Pure functions of the data, so the tests pin the format.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "teejet/valve.h"
#include "valve_table.hpp"

namespace teejet::valvectl {

// An aligned text table with a header line; a missing value shows as "-".
std::string render_table(const std::vector<ValveRow>& rows);
// One line per gateway: name, interface, bus state, valves online/known, frame counters.
std::string render_gateways(const std::vector<GatewaySummary>& gateways);

// {"serial":"TJV000001","address":216,"online":true,"position":45.0,"temperature_c":25,
//  "volts":12.0,"errors":["high_voltage"],"gateway":"..."}; missing values are null.
nlohmann::json to_json(const ValveRow& row);
nlohmann::json to_json(const std::vector<ValveRow>& rows);

// "TJV000002 target_degrees #17: ACCEPTED", "...: REJECTED: valve TJV000002 is offline".
std::string status_text(const CommandStatus& status);
// {"event":"status","serial":"TJV000002","command_id":17,"origin":"...","kind":"target_degrees",
//  "state":"accepted","reason":"","stamp_ns":...}
nlohmann::json status_json(const CommandStatus& status);

// "TJV000002 position 45.3"; {"event":"position","serial":"TJV000002","degrees":45.3}
std::string position_text(std::uint32_t serial, double degrees);
nlohmann::json position_json(std::uint32_t serial, double degrees);

// "TJV000006 voltage volts=12.0"; {"event":"reply","serial":..,"reply":"voltage","values":{..}}
std::string reply_text(std::uint32_t serial, const std::string& name, const Reply& reply);
nlohmann::json reply_json(std::uint32_t serial, const std::string& name, const Reply& reply);

// One decimal, as the wire resolves degrees and volts: 45 -> "45.0".
std::string one_decimal(double value);

// A value as the valve sent it, on the sheet's grid (`steps_per_unit` 10 for 0.1, 100 for
// 0.01), so that JSON, which prints the shortest decimal that reads back as the same double,
// prints what the valve sent: the float 74.6f on DDS is 74.59999847..., and 746 * 0.1 is
// 74.60000000000001; this gives the double nearest to 74.6, printed "74.6".
double at_resolution(float value, int steps_per_unit);

}  // namespace teejet::valvectl
