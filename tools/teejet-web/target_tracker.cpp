#include "target_tracker.hpp"

#include "teejet/client/json.hpp"

namespace teejet::web {

void TargetTracker::on_sent(const ValveCommand& command) {
  if (command.kind() == COMMAND_TARGET_DEGREES) {
    // The wire's float, at its 0.1 degree grid, as positions are shown.
    targets_[command.serial()] = client::at_resolution(command.degrees(), 10);
    running_[command.serial()] = command.command_id();
  } else {
    targets_.erase(command.serial());
    running_.erase(command.serial());
  }
}

void TargetTracker::on_status(const CommandStatus& status) {
  if (status.state() == COMMAND_ACCEPTED) return;
  const auto running = running_.find(status.serial());
  if (running == running_.end() || running->second != status.command_id()) return;
  running_.erase(running);
  targets_.erase(status.serial());
}

}  // namespace teejet::web
