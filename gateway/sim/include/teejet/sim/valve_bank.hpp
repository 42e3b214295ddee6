#pragma once

// A bank of simulated valves sharing one bus: address arbitration, routing by address and
// staggered I'm Here. Pure logic like SimulatedValve; the Simulator runs it on a bus.
//
// Arbitration (docs/valve-sim.md): valves are ranked by serial, lowest first, and the valve of
// rank r has address 0xD8 + r. Adding a valve re-ranks the bank, so every valve with a higher
// serial than the new one moves up one address, as the sheet warns can happen.

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "teejet/can/bus.hpp"
#include "teejet/sim/simulated_valve.hpp"

namespace teejet::sim {

inline constexpr std::size_t kMaxValves = 32;  // 0xD8 .. 0xF7
// I'm Here of the valve of rank r is offset by r * kIAmHereStagger, spreading a full bank of 32
// over the second.
inline constexpr Duration kIAmHereStagger = std::chrono::microseconds(31'250);

struct Outgoing {
  std::uint8_t address = 0;  // the sending valve
  codec::FromValveMessage message;
};

struct Assignment {
  std::uint32_t serial = 0;
  std::uint8_t address = 0;
  friend bool operator==(const Assignment&, const Assignment&) = default;
};

struct AddressChange {
  std::uint32_t serial = 0;
  std::optional<std::uint8_t> from;  // nullopt: the added valve
  std::uint8_t to = 0;
  friend bool operator==(const AddressChange&, const AddressChange&) = default;
};

class ValveBank {
 public:
  // Powers the valves up at `now`: ranks them, assigns the addresses and schedules the first
  // I'm Here of rank r at now + r * kIAmHereStagger. Refuses (and changes nothing) an empty or
  // invalid set, duplicate serials and more than 32 valves. Only for an empty bank.
  Status power_up(const std::vector<ValveConfig>& configs, SteadyTime now);

  // Adds a valve at run time and re-ranks. Every valve whose address changes, and the new one,
  // announces itself at its new address at now + rank * kIAmHereStagger and once a second
  // after; the others keep their rhythm. Motion, requests and errors are unaffected. A 33rd
  // valve, a duplicate serial or an invalid configuration is refused; nothing changes then.
  Status add_valve(const ValveConfig& config, SteadyTime now,
                   std::vector<AddressChange>* changes = nullptr);

  // Routes a controller message to the valve at `address`; nothing when none is there.
  std::vector<Outgoing> handle(std::uint8_t address, const codec::ToValveMessage& message,
                               SteadyTime now);
  std::vector<Outgoing> advance(SteadyTime now);
  std::optional<SteadyTime> next_due() const;

  Status inject_error(std::uint32_t serial, const InjectedError& error, SteadyTime now);

  std::size_t size() const { return valves_.size(); }
  std::vector<Assignment> assignments() const;  // by address
  std::optional<std::uint8_t> address_of(std::uint32_t serial) const;
  SimulatedValve* valve_at(std::uint8_t address);
  const SimulatedValve* valve_at(std::uint8_t address) const;
  const SimulatedValve* valve_with_serial(std::uint32_t serial) const;

 private:
  static std::uint8_t address_of_rank(std::size_t rank);
  std::vector<std::unique_ptr<SimulatedValve>> valves_;  // sorted by serial: index = rank
};

// The serial the command-line tool gives a valve added at run time (SIGUSR1): one below the
// lowest serial, so that it takes 0xD8 and every other valve moves up an address; when the
// lowest serial is 0, one above the highest (no reshuffle); nullopt when neither is free.
std::optional<std::uint32_t> serial_for_added_valve(const std::vector<Assignment>& bank);

}  // namespace teejet::sim
