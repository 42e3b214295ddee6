#pragma once

// A valve table as a gateway with a few valves would leave it, for the dashboard's tests.

#include <string>

#include "support/valve_samples.hpp"
#include "teejet/client/valve_table.hpp"

namespace teejet::web::testing {

using teejet::testing::presence;

// Valves 1 and 2 online, 3 offline, on gateway "gw".
inline client::ValveTable three_valves() {
  client::ValveTable table;
  table.on_presence(presence(1, true));
  table.on_presence(presence(2, true));
  table.on_presence(presence(3, false));
  return table;
}

}  // namespace teejet::web::testing
