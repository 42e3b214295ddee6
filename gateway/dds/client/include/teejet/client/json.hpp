#pragma once

// The JSON every client prints the same way: a valve's row and a command status, as valvectl
// --json writes them and teejet-web serves them. Pure functions of the data, so the tests pin the
// format.

#include <nlohmann/json.hpp>
#include <vector>

#include "teejet/client/valve_table.hpp"
#include "teejet/valve.h"

namespace teejet::client {

// {"serial":"TJV000001","address":216,"online":true,"position":45.0,"temperature_c":25,
//  "volts":12.0,"errors":["high_voltage"],"gateway":"..."}; missing values are null.
nlohmann::json to_json(const ValveRow& row);
nlohmann::json to_json(const std::vector<ValveRow>& rows);

// {"event":"status","serial":"TJV000002","command_id":17,"origin":"...","kind":"target_degrees",
//  "state":"accepted","reason":"","stamp_ns":...}
nlohmann::json status_json(const CommandStatus& status);

// A value as the valve sent it, on the sheet's grid (`steps_per_unit` 10 for 0.1, 100 for
// 0.01), so that JSON, which prints the shortest decimal that reads back as the same double,
// prints what the valve sent: the float 74.6f on DDS is 74.59999847..., and 746 * 0.1 is
// 74.60000000000001; this gives the double nearest to 74.6, printed "74.6".
double at_resolution(float value, int steps_per_unit);

}  // namespace teejet::client
