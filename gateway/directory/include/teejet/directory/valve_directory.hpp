#pragma once

// Who is on the bus: valves learned from I'm Here, keyed by serial number. An address is only
// where a valve is now; the sheet warns that adding a valve may move the others.

#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <vector>

#include "teejet/codec/messages.hpp"
#include "teejet/core/time.hpp"

namespace teejet::directory {

struct ValveRecord {
  std::uint32_t serial = 0;
  std::uint8_t address = 0;  // where the valve last announced itself
  bool online = false;
  std::uint32_t part_number = 0;
  bool boot_mode = false;
  Timestamp last_seen{};    // wall-clock receive time of the last I'm Here, for people
  SteadyTime last_heard{};  // the same instant on the steady clock, for the offline timeout
  friend bool operator==(const ValveRecord&, const ValveRecord&) = default;
};

enum class ChangeKind {
  kAppeared,     // first I'm Here from this serial
  kReaddressed,  // the same serial announced from another address
  kCameOnline,   // announced again after being offline
  kWentOffline,  // no I'm Here within the offline timeout
  // Another valve announced itself at this valve's address: where this one is now is unknown
  // until it announces again, so it is offline (nothing may be sent to its old address).
  kDisplaced,
  kModeChanged,  // boot mode or part number changed
  // Two valves both keep announcing at one address (faulty firmware, a miswired bench): neither
  // can be told apart on the bus. Reported once for each of them, `other` the second serial.
  kAddressConflict,
  // The conflict is over: the other valve moved away or went silent; `valve` holds the address.
  kConflictCleared,
};

const char* to_string(ChangeKind kind);

struct Change {
  ChangeKind kind;
  ValveRecord valve;                             // the state after the change
  std::optional<std::uint8_t> previous_address;  // set for kReaddressed and kDisplaced
  std::optional<std::uint32_t> other;            // set for kAddressConflict, kConflictCleared
  friend bool operator==(const Change&, const Change&) = default;
};

// An address two valves claim. `confirmed` once both have announced there after the contest
// began; before that it is only suspected (a valve that was just readdressed may still move on).
struct Contest {
  std::uint8_t address = 0;
  std::uint32_t holder = 0;    // announced there first
  std::uint32_t claimant = 0;  // came back to it while the holder was still there
  bool confirmed = false;
  friend bool operator==(const Contest&, const Contest&) = default;
};

class ValveDirectory {
 public:
  explicit ValveDirectory(std::chrono::nanoseconds offline_after = std::chrono::seconds(3));

  // Learns from one I'm Here, received at `received` (wall clock) and handled at `now`, and
  // returns what changed (nothing for a routine heartbeat). A valve that held the address until
  // now is displaced (reported first).
  std::vector<Change> on_i_am_here(std::uint8_t address, const codec::IAmHere& message,
                                   Timestamp received, SteadyTime now);

  // Marks valves offline whose last I'm Here is older than the timeout at `now`.
  std::vector<Change> expire(SteadyTime now);

  // The online valve that last announced itself at `address`: whose telemetry this is. Nobody
  // while the address is contested: its telemetry could be either valve's.
  std::optional<std::uint32_t> serial_at(std::uint8_t address) const;

  // The contest `serial` is part of, suspected or confirmed; nullopt when none.
  std::optional<Contest> contest_of(std::uint32_t serial) const;

  std::optional<ValveRecord> find(std::uint32_t serial) const;
  std::vector<ValveRecord> valves() const;  // ordered by serial
  std::size_t online_count() const;

  // When the next valve would go offline if nothing arrives; nullopt when none is online.
  std::optional<SteadyTime> next_expiry() const;

 private:
  // `serial` announced at `address`: a contest it was part of elsewhere is over.
  void leave_contests(std::uint32_t serial, std::uint8_t address, std::vector<Change>& changes);
  // The contest at `address` is over and `remaining` holds the address.
  void end_contest(std::uint8_t address, std::uint32_t remaining, std::uint32_t gone,
                   std::vector<Change>& changes);

  std::chrono::nanoseconds offline_after_;
  std::map<std::uint32_t, ValveRecord> by_serial_;
  std::map<std::uint8_t, std::uint32_t> serial_by_address_;
  std::map<std::uint8_t, Contest> contests_;
  // Displaced valves: offline already, but reported kWentOffline once their I'm Here is older
  // than the timeout, so that what they were asked ends no later than for a silent valve.
  std::map<std::uint32_t, SteadyTime> displaced_;
};

}  // namespace teejet::directory
