#include "teejet/directory/valve_directory.hpp"

namespace teejet::directory {

const char* to_string(ChangeKind kind) {
  switch (kind) {
    case ChangeKind::kAppeared:
      return "appeared";
    case ChangeKind::kReaddressed:
      return "readdressed";
    case ChangeKind::kCameOnline:
      return "came online";
    case ChangeKind::kWentOffline:
      return "went offline";
    case ChangeKind::kDisplaced:
      return "displaced";
    case ChangeKind::kModeChanged:
      return "mode changed";
  }
  return "unknown";
}

ValveDirectory::ValveDirectory(std::chrono::nanoseconds offline_after)
    : offline_after_(offline_after) {}

std::vector<Change> ValveDirectory::on_i_am_here(std::uint8_t address,
                                                 const codec::IAmHere& message, Timestamp received,
                                                 SteadyTime now) {
  std::vector<Change> changes;
  // Whoever announced here before has moved (or is gone): the address now means this serial.
  auto [slot, fresh] = serial_by_address_.try_emplace(address, message.serial);
  if (!fresh && slot->second != message.serial) {
    ValveRecord& previous = by_serial_.at(slot->second);
    if (previous.address == address && previous.online) {
      previous.online = false;
      changes.push_back({ChangeKind::kDisplaced, previous, address});
    }
  }
  slot->second = message.serial;

  auto [it, inserted] = by_serial_.try_emplace(message.serial);
  ValveRecord& valve = it->second;
  const ValveRecord before = valve;
  valve = {message.serial, address, true, message.part_number, message.boot_mode, received, now};

  if (inserted) {
    changes.push_back({ChangeKind::kAppeared, valve, std::nullopt});
    return changes;
  }
  if (before.address != address) {
    // Only drop the old mapping if it still points at this valve; another may have moved in.
    if (auto old = serial_by_address_.find(before.address);
        old != serial_by_address_.end() && old->second == message.serial) {
      serial_by_address_.erase(old);
    }
    changes.push_back({ChangeKind::kReaddressed, valve, before.address});
  }
  if (!before.online) changes.push_back({ChangeKind::kCameOnline, valve, std::nullopt});
  if (before.boot_mode != valve.boot_mode || before.part_number != valve.part_number) {
    changes.push_back({ChangeKind::kModeChanged, valve, std::nullopt});
  }
  return changes;
}

std::vector<Change> ValveDirectory::expire(SteadyTime now) {
  std::vector<Change> changes;
  for (auto& [serial, valve] : by_serial_) {
    if (valve.online && now - valve.last_heard > offline_after_) {
      valve.online = false;
      changes.push_back({ChangeKind::kWentOffline, valve, std::nullopt});
    }
  }
  return changes;
}

std::optional<std::uint32_t> ValveDirectory::serial_at(std::uint8_t address) const {
  auto it = serial_by_address_.find(address);
  if (it == serial_by_address_.end()) return std::nullopt;
  const auto& valve = by_serial_.at(it->second);
  if (!valve.online || valve.address != address) return std::nullopt;
  return it->second;
}

std::optional<ValveRecord> ValveDirectory::find(std::uint32_t serial) const {
  auto it = by_serial_.find(serial);
  if (it == by_serial_.end()) return std::nullopt;
  return it->second;
}

std::vector<ValveRecord> ValveDirectory::valves() const {
  std::vector<ValveRecord> out;
  out.reserve(by_serial_.size());
  for (const auto& [serial, valve] : by_serial_) out.push_back(valve);
  return out;
}

std::size_t ValveDirectory::online_count() const {
  std::size_t count = 0;
  for (const auto& [serial, valve] : by_serial_) count += valve.online ? 1 : 0;
  return count;
}

std::optional<SteadyTime> ValveDirectory::next_expiry() const {
  std::optional<SteadyTime> earliest;
  for (const auto& [serial, valve] : by_serial_) {
    if (!valve.online) continue;
    const SteadyTime due = valve.last_heard + offline_after_;
    if (!earliest || due < *earliest) earliest = due;
  }
  return earliest;
}

}  // namespace teejet::directory
