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
};

const char* to_string(ChangeKind kind);

struct Change {
  ChangeKind kind;
  ValveRecord valve;                             // the state after the change
  std::optional<std::uint8_t> previous_address;  // set for kReaddressed and kDisplaced
  friend bool operator==(const Change&, const Change&) = default;
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

  // The online valve that last announced itself at `address`: whose telemetry this is.
  std::optional<std::uint32_t> serial_at(std::uint8_t address) const;

  std::optional<ValveRecord> find(std::uint32_t serial) const;
  std::vector<ValveRecord> valves() const;  // ordered by serial
  std::size_t online_count() const;

  // When the next valve would go offline if nothing arrives; nullopt when none is online.
  std::optional<SteadyTime> next_expiry() const;

 private:
  std::chrono::nanoseconds offline_after_;
  std::map<std::uint32_t, ValveRecord> by_serial_;
  std::map<std::uint8_t, std::uint32_t> serial_by_address_;
};

}  // namespace teejet::directory
