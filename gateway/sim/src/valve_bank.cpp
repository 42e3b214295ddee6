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
  for (const auto& config : configs) valves_.push_back(std::make_unique<SimulatedValve>(config));
  std::sort(valves_.begin(), valves_.end(),
            [](const auto& a, const auto& b) { return a->serial() < b->serial(); });
  for (std::size_t rank = 0; rank < valves_.size(); ++rank) {
    valves_[rank]->schedule_i_am_here(now + static_cast<Duration::rep>(rank) * kIAmHereStagger);
  }
  return {};
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
                               [&](const auto& v) { return v->serial() > config.serial; });
  const auto rank_of_new = static_cast<std::size_t>(at - valves_.begin());
  valves_.insert(at, std::make_unique<SimulatedValve>(config));
  if (changes) changes->clear();
  // The new valve and every valve above it in rank take a new address and announce it.
  for (std::size_t rank = rank_of_new; rank < valves_.size(); ++rank) {
    auto& valve = *valves_[rank];
    valve.schedule_i_am_here(now + static_cast<Duration::rep>(rank) * kIAmHereStagger);
    if (changes) {
      std::optional<std::uint8_t> from;
      if (rank != rank_of_new) from = address_of_rank(rank - 1);
      changes->push_back({valve.serial(), from, address_of_rank(rank)});
    }
  }
  return {};
}

std::vector<Outgoing> ValveBank::handle(std::uint8_t address, const codec::ToValveMessage& message,
                                        SteadyTime now) {
  std::vector<Outgoing> out;
  if (auto* valve = valve_at(address)) {
    for (auto& reply : valve->handle(message, now)) out.push_back({address, std::move(reply)});
  }
  return out;
}

std::vector<Outgoing> ValveBank::advance(SteadyTime now) {
  std::vector<Outgoing> out;
  for (std::size_t rank = 0; rank < valves_.size(); ++rank) {
    for (auto& message : valves_[rank]->advance(now)) {
      out.push_back({address_of_rank(rank), std::move(message)});
    }
  }
  return out;
}

std::optional<SteadyTime> ValveBank::next_due() const {
  std::optional<SteadyTime> earliest;
  for (const auto& valve : valves_) {
    const auto due = valve->next_due();
    if (due && (!earliest || *due < *earliest)) earliest = due;
  }
  return earliest;
}

Status ValveBank::inject_error(std::uint32_t serial, const InjectedError& error, SteadyTime now) {
  if (const auto valid = validate(error); !valid) return valid;
  for (auto& valve : valves_) {
    if (valve->serial() == serial) {
      valve->inject_error(error, now);
      return {};
    }
  }
  return Error{ErrorCode::kInvalidValue, "no valve with serial " + codec::format_serial(serial)};
}

std::vector<Assignment> ValveBank::assignments() const {
  std::vector<Assignment> result;
  for (std::size_t rank = 0; rank < valves_.size(); ++rank) {
    result.push_back({valves_[rank]->serial(), address_of_rank(rank)});
  }
  return result;
}

std::optional<std::uint8_t> ValveBank::address_of(std::uint32_t serial) const {
  for (std::size_t rank = 0; rank < valves_.size(); ++rank) {
    if (valves_[rank]->serial() == serial) return address_of_rank(rank);
  }
  return std::nullopt;
}

SimulatedValve* ValveBank::valve_at(std::uint8_t address) {
  if (!codec::is_valve_address(address)) return nullptr;
  const auto rank = static_cast<std::size_t>(address - codec::kFirstValveAddress);
  return rank < valves_.size() ? valves_[rank].get() : nullptr;
}

const SimulatedValve* ValveBank::valve_at(std::uint8_t address) const {
  return const_cast<ValveBank*>(this)->valve_at(address);
}

const SimulatedValve* ValveBank::valve_with_serial(std::uint32_t serial) const {
  for (const auto& valve : valves_) {
    if (valve->serial() == serial) return valve.get();
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
