#pragma once

// A token bucket per valve for the commands the bridge sends: one writer flooding one valve
// would otherwise fill the bus (a 250 kbit/s bus carries ~2,000 frames/s) and starve every
// other valve's commands. Stop has a bucket of its own, so that a flood of moves can never use
// up a commander's ability to stop the valve, and a flood of Stops is bounded all the same.

#include <cstdint>
#include <map>
#include <utility>

#include "teejet/core/time.hpp"

namespace teejet::bridge {

class CommandRateLimiter {
 public:
  // `per_second` 0: no limit. `burst`: commands a quiet valve takes at once.
  CommandRateLimiter(double per_second, double burst) : per_second_(per_second), burst_(burst) {}

  // Takes a token from the valve's bucket (its Stop bucket if `stop`); false when it is empty.
  bool admit(std::uint32_t serial, bool stop, SteadyTime now);

 private:
  struct Bucket {
    double tokens;
    SteadyTime refilled;
  };
  const double per_second_;
  const double burst_;
  std::map<std::pair<std::uint32_t, bool>, Bucket> buckets_;
};

}  // namespace teejet::bridge
