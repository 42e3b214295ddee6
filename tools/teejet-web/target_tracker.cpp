#include "target_tracker.hpp"

#include "teejet/codec/table.hpp"
#include "teejet/dds/conversions.hpp"

namespace teejet::web {

void TargetTracker::on_sent(const ValveCommand& command) {
  if (command.kind() == COMMAND_TARGET_DEGREES) {
    // The wire's float, on the field's grid, as positions are shown.
    if (const auto move = dds::to_message(command)) {
      targets_[command.serial()] = std::get<codec::TargetDegrees>(codec::as_sent(*move)).degrees;
    }
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
