#pragma once

// A valve table as a gateway with a few valves would leave it, and a sender that records what
// would have gone to DDS, for the dashboard's tests.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "page_command.hpp"
#include "support/valve_samples.hpp"
#include "teejet/client/valve_table.hpp"

namespace teejet::web::testing {

using teejet::testing::location;
using teejet::testing::presence;

// Valves 1 and 2 online, 3 offline, on gateway "gw".
inline client::ValveTable three_valves() {
  client::ValveTable table;
  table.on_presence(presence(1, true));
  table.on_presence(presence(2, true));
  table.on_presence(presence(3, false));
  return table;
}

// three_valves() on gateway "gw" (participant "01.0f.aa") with a layout: section-01 holds
// TJV000001, section-02 TJV000002, section-03 is empty, section-04 waits for the unseen TJV000009;
// "twice" is also claimed by gateway "gw2" (participant "01.0f.bb").
inline client::ValveTable three_valves_on_a_boom() {
  client::ValveTable table = three_valves();
  table.on_location(location("section-01", "gw", 1, 1, LOCATION_OK), "01.0f.aa");
  table.on_location(location("section-02", "gw", 2, 2, LOCATION_OK), "01.0f.aa");
  table.on_location(location("section-03", "gw", 3, std::nullopt, LOCATION_EMPTY), "01.0f.aa");
  table.on_location(location("section-04", "gw", 4, 9, LOCATION_MISSING), "01.0f.aa");
  table.on_location(location("twice", "gw", 5, std::nullopt, LOCATION_EMPTY), "01.0f.aa");
  table.on_location(location("twice", "gw2", 1, std::nullopt, LOCATION_EMPTY), "01.0f.bb");
  return table;
}

// Records what would have been written to DDS.
class RecordingSender final : public CommandSender {
 public:
  Result<std::uint32_t> send(ValveCommand command) override {
    if (failing) return Error{ErrorCode::kInvalidValue, "no gateway subscribes to commands"};
    command.command_id(next_id_++);
    sent.push_back(command);
    return command.command_id();
  }
  Result<std::uint32_t> send(LayoutChange change, const std::string& participant) override {
    if (failing) return Error{ErrorCode::kInvalidValue, "gateway gw did not subscribe"};
    change.change_id(next_id_++);
    changes.emplace_back(change, participant);
    return change.change_id();
  }
  bool failing = false;
  std::vector<ValveCommand> sent;
  std::vector<std::pair<LayoutChange, std::string>> changes;  // with the gateway's participant

 private:
  std::uint32_t next_id_ = 100;
};

}  // namespace teejet::web::testing
