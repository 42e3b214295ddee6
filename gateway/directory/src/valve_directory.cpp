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
    case ChangeKind::kAddressConflict:
      return "address conflict";
    case ChangeKind::kConflictCleared:
      return "conflict cleared";
  }
  return "unknown";
}

ValveDirectory::ValveDirectory(std::chrono::nanoseconds offline_after)
    : offline_after_(offline_after) {}

std::vector<Change> ValveDirectory::on_i_am_here(std::uint8_t address,
                                                 const codec::IAmHere& message, Timestamp received,
                                                 SteadyTime now) {
  std::vector<Change> changes;
  const std::uint32_t serial = message.serial;
  displaced_.erase(serial);
  leave_contests(serial, address, changes);
  const auto recent = [&](const ValveRecord& valve) {
    return now - valve.last_heard <= offline_after_;
  };

  auto contest = contests_.find(address);
  if (contest != contests_.end() && contest->second.holder != serial &&
      contest->second.claimant != serial) {
    // A third valve: the two before it are displaced like any previous holder (below).
    for (const auto member : {contest->second.holder, contest->second.claimant}) {
      ValveRecord& valve = by_serial_.at(member);
      if (valve.address == address && valve.online) {
        valve.online = false;
        displaced_[member] = valve.last_heard;
        changes.push_back({ChangeKind::kDisplaced, valve, address});
      }
    }
    contests_.erase(contest);
    contest = contests_.end();
  }
  bool contested = contest != contests_.end();
  if (contested && !contest->second.confirmed && contest->second.holder == serial) {
    // The holder announced here again after the claimant did: both really are at this address.
    contest->second.confirmed = true;
    for (const auto member : {contest->second.holder, contest->second.claimant}) {
      const auto other =
          member == contest->second.holder ? contest->second.claimant : contest->second.holder;
      changes.push_back({ChangeKind::kAddressConflict, by_serial_.at(member), std::nullopt, other});
    }
  }

  auto slot = serial_by_address_.find(address);
  if (!contested && slot != serial_by_address_.end() && slot->second != serial) {
    ValveRecord& previous = by_serial_.at(slot->second);
    const auto mine = by_serial_.find(serial);
    // Back at the address it announced at within the timeout, while the valve that took it is
    // still there too: either one of them moves on (a readdress in progress) or both stay (a
    // conflict, confirmed when the holder announces here again).
    const bool reclaims = mine != by_serial_.end() && mine->second.address == address &&
                          recent(mine->second) && previous.address == address && previous.online &&
                          recent(previous);
    if (reclaims) {
      contests_[address] = Contest{address, slot->second, serial, false};
      contested = true;
    } else if (previous.address == address && previous.online) {
      // Whoever announced here before has moved (or is gone): the address now means this one.
      previous.online = false;
      displaced_[previous.serial] = previous.last_heard;
      changes.push_back({ChangeKind::kDisplaced, previous, address});
    }
  }
  if (!contested) serial_by_address_[address] = serial;

  auto [it, inserted] = by_serial_.try_emplace(serial);
  ValveRecord& valve = it->second;
  const ValveRecord before = valve;
  valve = {serial, address, true, message.part_number, message.boot_mode, received, now};

  if (inserted) {
    changes.push_back({ChangeKind::kAppeared, valve, std::nullopt});
    return changes;
  }
  if (before.address != address) {
    // Only drop the old mapping if it still points at this valve; another may have moved in.
    if (auto old = serial_by_address_.find(before.address);
        old != serial_by_address_.end() && old->second == serial) {
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

void ValveDirectory::leave_contests(std::uint32_t serial, std::uint8_t address,
                                    std::vector<Change>& changes) {
  std::vector<Contest> left;
  for (const auto& [at, contest] : contests_) {
    if (at != address && (contest.holder == serial || contest.claimant == serial)) {
      left.push_back(contest);
    }
  }
  for (const auto& contest : left) {
    end_contest(contest.address, contest.holder == serial ? contest.claimant : contest.holder,
                serial, changes);
  }
}

void ValveDirectory::end_contest(std::uint8_t address, std::uint32_t remaining, std::uint32_t gone,
                                 std::vector<Change>& changes) {
  const auto it = contests_.find(address);
  if (it == contests_.end()) return;
  const bool confirmed = it->second.confirmed;
  contests_.erase(it);
  serial_by_address_[address] = remaining;
  if (confirmed) {
    changes.push_back({ChangeKind::kConflictCleared, by_serial_.at(remaining), std::nullopt, gone});
  }
}

std::vector<Change> ValveDirectory::expire(SteadyTime now) {
  std::vector<Change> changes;
  for (auto& [serial, valve] : by_serial_) {
    if (valve.online && now - valve.last_heard > offline_after_) {
      valve.online = false;
      changes.push_back({ChangeKind::kWentOffline, valve, std::nullopt});
      if (const auto contest = contest_of(serial)) {
        end_contest(contest->address,
                    contest->holder == serial ? contest->claimant : contest->holder, serial,
                    changes);
      }
    }
  }
  for (auto it = displaced_.begin(); it != displaced_.end();) {
    if (now - it->second > offline_after_) {
      changes.push_back({ChangeKind::kWentOffline, by_serial_.at(it->first), std::nullopt});
      it = displaced_.erase(it);
    } else {
      ++it;
    }
  }
  return changes;
}

std::optional<Contest> ValveDirectory::contest_of(std::uint32_t serial) const {
  for (const auto& [address, contest] : contests_) {
    if (contest.holder == serial || contest.claimant == serial) return contest;
  }
  return std::nullopt;
}

std::optional<std::uint32_t> ValveDirectory::serial_at(std::uint8_t address) const {
  if (contests_.contains(address)) return std::nullopt;
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
  for (const auto& [serial, last_heard] : displaced_) {
    const SteadyTime due = last_heard + offline_after_;
    if (!earliest || due < *earliest) earliest = due;
  }
  return earliest;
}

}  // namespace teejet::directory
