#include "teejet/sim/valve_bank.hpp"

#include <algorithm>
#include <set>

#include "teejet/codec/codec.hpp"

namespace teejet::sim {
namespace {

std::string too_many(std::size_t count) {
  return std::to_string(count) + " valves do not fit the " + std::to_string(kMaxValves) +
         " addresses 0xD8-0xF7";
}

}  // namespace

std::uint8_t ValveBank::address_of_rank(std::size_t rank) {
  return static_cast<std::uint8_t>(codec::kFirstValveAddress + rank);
}

Status ValveBank::power_up(const std::vector<ValveConfig>& configs, SteadyTime now) {
  if (!valves_.empty()) return Error{ErrorCode::kInvalidValue, "the bank is already powered up"};
  if (configs.empty()) return Error{ErrorCode::kInvalidValue, "no valves to simulate"};
  if (configs.size() > kMaxValves) return Error{ErrorCode::kInvalidValue, too_many(configs.size())};
  std::set<std::uint32_t> serials;
  for (const auto& config : configs) {
    if (const auto valid = validate(config); !valid) return valid;
    if (!serials.insert(config.serial).second) {
      return Error{ErrorCode::kInvalidValue,
                   "serial " + codec::format_serial(config.serial) + " is given twice"};
    }
  }
  for (const auto& config : configs) {
    valves_.push_back(Slot{std::make_unique<SimulatedValve>(config), std::nullopt});
  }
  std::sort(valves_.begin(), valves_.end(),
            [](const Slot& a, const Slot& b) { return a.valve->serial() < b.valve->serial(); });
  rerank(now, nullptr);
  return {};
}

void ValveBank::rerank(SteadyTime now, std::vector<AddressChange>* changes) {
  if (changes) changes->clear();
  std::size_t rank = 0;
  for (auto& slot : valves_) {
    if (!slot.valve->powered()) continue;
    const auto address = address_of_rank(rank);
    if (slot.address != address) {
      slot.valve->schedule_i_am_here(now + static_cast<Duration::rep>(rank) * kIAmHereStagger);
      if (changes) changes->push_back({slot.valve->serial(), slot.address, address});
      slot.address = address;
    }
    ++rank;
  }
}

ValveBank::Slot* ValveBank::slot_of(std::uint32_t serial) {
  for (auto& slot : valves_) {
    if (slot.valve->serial() == serial) return &slot;
  }
  return nullptr;
}

Status ValveBank::add_valve(const ValveConfig& config, SteadyTime now,
                            std::vector<AddressChange>* changes) {
  if (const auto valid = validate(config); !valid) return valid;
  if (valve_with_serial(config.serial) != nullptr) {
    return Error{
        ErrorCode::kInvalidValue,
        "a valve with serial " + codec::format_serial(config.serial) + " is already on the bus"};
  }
  if (valves_.size() >= kMaxValves) {
    return Error{ErrorCode::kInvalidValue, "cannot add " + codec::format_serial(config.serial) +
                                               ": " + too_many(valves_.size() + 1)};
  }
  const auto at = std::find_if(valves_.begin(), valves_.end(),
                               [&](const Slot& s) { return s.valve->serial() > config.serial; });
  valves_.insert(at, Slot{std::make_unique<SimulatedValve>(config), std::nullopt});
  rerank(now, changes);
  return {};
}

Status ValveBank::power_off(std::uint32_t serial, SteadyTime now,
                            std::vector<AddressChange>* changes) {
  auto* slot = slot_of(serial);
  if (slot == nullptr) {
    return Error{ErrorCode::kInvalidValue, "no valve with serial " + codec::format_serial(serial)};
  }
  if (!slot->valve->powered()) {
    return Error{ErrorCode::kInvalidValue, codec::format_serial(serial) + " is already off"};
  }
  slot->valve->power_off(now);
  slot->address.reset();
  rerank(now, changes);
  return {};
}

Status ValveBank::power_on(std::uint32_t serial, bool boot_mode, SteadyTime now,
                           std::vector<AddressChange>* changes) {
  auto* slot = slot_of(serial);
  if (slot == nullptr) {
    return Error{ErrorCode::kInvalidValue, "no valve with serial " + codec::format_serial(serial)};
  }
  if (slot->valve->powered()) {
    return Error{ErrorCode::kInvalidValue, codec::format_serial(serial) + " is already on"};
  }
  slot->valve->power_on(boot_mode);
  rerank(now, changes);
  return {};
}

Status ValveBank::force_address(std::uint32_t serial, std::uint8_t address, SteadyTime now) {
  auto* slot = slot_of(serial);
  if (slot == nullptr) {
    return Error{ErrorCode::kInvalidValue, "no valve with serial " + codec::format_serial(serial)};
  }
  if (!slot->valve->powered()) {
    return Error{ErrorCode::kInvalidValue, codec::format_serial(serial) + " is off"};
  }
  if (!codec::is_valve_address(address)) {
    return Error{ErrorCode::kInvalidValue, "not a valve address (0xD8-0xF7)"};
  }
  slot->address = address;
  slot->valve->schedule_i_am_here(now);
  return {};
}

std::vector<Outgoing> ValveBank::handle(std::uint8_t address, const codec::ToValveMessage& message,
                                        SteadyTime now) {
  std::vector<Outgoing> out;
  for (auto& slot : valves_) {
    if (slot.address != address) continue;
    for (auto& reply : slot.valve->handle(message, now)) out.push_back({address, std::move(reply)});
  }
  return out;
}

std::vector<Outgoing> ValveBank::advance(SteadyTime now) {
  std::vector<Outgoing> out;
  for (auto& slot : valves_) {
    if (!slot.address) continue;
    for (auto& message : slot.valve->advance(now))
      out.push_back({*slot.address, std::move(message)});
  }
  return out;
}

std::optional<SteadyTime> ValveBank::next_due() const {
  std::optional<SteadyTime> earliest;
  for (const auto& slot : valves_) {
    const auto due = slot.valve->next_due();
    if (due && (!earliest || *due < *earliest)) earliest = due;
  }
  return earliest;
}

Status ValveBank::inject_error(std::uint32_t serial, const InjectedError& error, SteadyTime now) {
  if (const auto valid = validate(error); !valid) return valid;
  auto* slot = slot_of(serial);
  if (slot == nullptr) {
    return Error{ErrorCode::kInvalidValue, "no valve with serial " + codec::format_serial(serial)};
  }
  slot->valve->inject_error(error, now);
  return {};
}

std::vector<Assignment> ValveBank::assignments() const {
  std::vector<Assignment> result;
  for (const auto& slot : valves_) {
    if (slot.address) result.push_back({slot.valve->serial(), *slot.address});
  }
  std::stable_sort(result.begin(), result.end(),
                   [](const Assignment& a, const Assignment& b) { return a.address < b.address; });
  return result;
}

std::optional<std::uint8_t> ValveBank::address_of(std::uint32_t serial) const {
  for (const auto& slot : valves_) {
    if (slot.valve->serial() == serial) return slot.address;
  }
  return std::nullopt;
}

SimulatedValve* ValveBank::valve_at(std::uint8_t address) {
  for (auto& slot : valves_) {
    if (slot.address == address) return slot.valve.get();
  }
  return nullptr;
}

const SimulatedValve* ValveBank::valve_at(std::uint8_t address) const {
  return const_cast<ValveBank*>(this)->valve_at(address);
}

const SimulatedValve* ValveBank::valve_with_serial(std::uint32_t serial) const {
  for (const auto& slot : valves_) {
    if (slot.valve->serial() == serial) return slot.valve.get();
  }
  return nullptr;
}

std::optional<std::uint32_t> serial_for_added_valve(const std::vector<Assignment>& bank) {
  if (bank.empty()) return 1;
  if (bank.size() >= kMaxValves) return std::nullopt;
  const auto [lowest, highest] = std::minmax_element(
      bank.begin(), bank.end(),
      [](const Assignment& a, const Assignment& b) { return a.serial < b.serial; });
  if (lowest->serial > 0) return lowest->serial - 1;
  if (highest->serial < kMaxSerial) return highest->serial + 1;
  return std::nullopt;
}

}  // namespace teejet::sim
