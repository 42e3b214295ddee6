#pragma once

// A bank of simulated valves sharing one bus: address arbitration, routing by address and
// staggered I'm Here. Pure logic like SimulatedValve; the Simulator runs it on a bus.
//
// Arbitration (docs/valve-sim.md): the valves that are on are ranked by serial, lowest first,
// and the valve of rank r has address 0xD8 + r. Adding a valve, or one going off or coming back,
// re-ranks the bank, so the valves with a higher serial move, as the sheet warns can happen.
// force_address() breaks the rule on purpose: a valve claiming an address another one holds.

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

  // Power gone: the valve goes silent (SimulatedValve::power_off) and leaves the ranking, so
  // every valve above it moves down one address and announces there. Refused for an unknown
  // serial or a valve already off.
  Status power_off(std::uint32_t serial, SteadyTime now,
                   std::vector<AddressChange>* changes = nullptr);
  // Power back: the valve is re-ranked like an added one (its change has no `from`), valves
  // above it move up, and it announces itself, with the boot code flag when `boot_mode`.
  // Refused for an unknown serial or a valve already on.
  Status power_on(std::uint32_t serial, bool boot_mode, SteadyTime now,
                  std::vector<AddressChange>* changes = nullptr);
  // Faulty firmware or a miswired bench: the valve claims `address` whoever holds it, and
  // announces itself there at once and once a second after. Both valves at a contested address
  // act on what is sent to it. Lasts until the valve goes off or the bank is re-ranked.
  Status force_address(std::uint32_t serial, std::uint8_t address, SteadyTime now);

  // Routes a controller message to the valves at `address` (normally one); nothing when none
  // is there.
  std::vector<Outgoing> handle(std::uint8_t address, const codec::ToValveMessage& message,
                               SteadyTime now);
  std::vector<Outgoing> advance(SteadyTime now);
  std::optional<SteadyTime> next_due() const;

  Status inject_error(std::uint32_t serial, const InjectedError& error, SteadyTime now);

  std::size_t size() const { return valves_.size(); }  // on and off
  std::vector<Assignment> assignments() const;         // the valves that are on, by address
  std::optional<std::uint8_t> address_of(std::uint32_t serial) const;  // nullopt: off or unknown
  // The valve at `address` (the lowest serial when it is contested).
  SimulatedValve* valve_at(std::uint8_t address);
  const SimulatedValve* valve_at(std::uint8_t address) const;
  const SimulatedValve* valve_with_serial(std::uint32_t serial) const;

 private:
  struct Slot {
    std::unique_ptr<SimulatedValve> valve;
    std::optional<std::uint8_t> address;  // nullopt while off
  };
  static std::uint8_t address_of_rank(std::size_t rank);
  Slot* slot_of(std::uint32_t serial);
  // Gives the valves that are on the addresses of their ranks (ending any forced address); each
  // whose address changed announces at now + rank * kIAmHereStagger.
  void rerank(SteadyTime now, std::vector<AddressChange>* changes);
  std::vector<Slot> valves_;  // sorted by serial
};

// The serial the command-line tool gives a valve added at run time (SIGUSR1): one below the
// lowest serial, so that it takes 0xD8 and every other valve moves up an address; when the
// lowest serial is 0, one above the highest (no reshuffle); nullopt when neither is free.
std::optional<std::uint32_t> serial_for_added_valve(const std::vector<Assignment>& bank);

}  // namespace teejet::sim
