#pragma once

// Every command a soak sends and the final state each one got: a command without exactly one
// final state is a commander left guessing, the thing the soak exists to catch. Pure and
// thread-safe (statuses arrive on Fast DDS's threads while the soak sends).

#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <unordered_map>

#include "teejet/valve.h"

namespace teejet::bench {

struct LedgerCounts {
  std::uint32_t sent = 0;
  std::uint32_t accepted = 0;
  std::uint32_t completed = 0;
  std::uint32_t superseded = 0;
  std::uint32_t timed_out = 0;
  std::uint32_t rejected = 0;
  std::uint32_t unaccounted = 0;       // sent, no final state (yet)
  std::uint32_t duplicate_finals = 0;  // a second final state for one command
  std::uint32_t unknown = 0;           // a status for a command id never sent
  // Why commands were REJECTED or TIMED_OUT, numbers masked ("valve TJV* is offline"), so that
  // one reason is one line however many valves and positions gave it.
  std::map<std::string, std::uint32_t> reasons;
};

class CommandLedger {
 public:
  // The id of the next command, counted as sent.
  std::uint32_t next_id();
  // A status written by the gateway for one of our commands.
  void record(const CommandStatus& status);
  LedgerCounts counts() const;
  std::uint32_t unaccounted() const;

 private:
  mutable std::mutex mutex_;
  std::uint32_t sent_ = 0;
  LedgerCounts counts_;
  std::unordered_map<std::uint32_t, CommandState> final_state_;
};

// Every number masked: "TJV000012 took its address 0xD9" → "TJV* took its address 0x*",
// "position 29.4 did not reach 80.0" → "position * did not reach *".
std::string mask_numbers(const std::string& reason);

}  // namespace teejet::bench
