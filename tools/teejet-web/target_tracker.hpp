#pragma once

// The "target" of each valve on the dashboard: where the Target Degrees move that teejet-web
// itself sent is heading. Only its own moves, since statuses of other senders are not followed.

#include <cstdint>
#include <map>

#include "teejet/valve.h"

namespace teejet::web {

// The target, in degrees, of the running Target Degrees command per valve, by serial.
using Targets = std::map<std::uint32_t, double>;

// A Target Degrees command sets the target of its valve; any other command to the valve or a
// final status of the move clears it.
class TargetTracker {
 public:
  void on_sent(const ValveCommand& command);  // serial and command_id set
  void on_status(const CommandStatus& status);
  const Targets& targets() const { return targets_; }

 private:
  Targets targets_;
  std::map<std::uint32_t, std::uint32_t> running_;  // command_id of each target, by serial
};

}  // namespace teejet::web
