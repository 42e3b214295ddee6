#pragma once

// Whether the bus is busy enough for the bus reader to coalesce its wake-ups
// (gateway.receive_coalesce_above_fps). Judged over the last second, in steps of a tenth: a bus
// whose frames come in bursts (a poll's replies, one after another at wire speed) carries more
// than its average in some tenths and less in the next, and a tenth alone would call a
// three-quarters-full bus busy now and then and hold its frames up for the window.

#include <array>
#include <cstddef>

#include "teejet/core/time.hpp"

namespace teejet::gateway {

class BusRate {
 public:
  static constexpr Duration kStep = std::chrono::milliseconds(100);
  static constexpr std::size_t kSteps = 10;  // the last second

  // above 0: busy at any rate, from the start.
  BusRate(unsigned above, SteadyTime now);

  // `frames` taken at `now`.
  void count(std::size_t frames, SteadyTime now);

  // At least `above` frames a second over the last second, and over its last tenth: a bus that
  // quietened is no longer busy after one tenth. Not busy before a second was counted.
  bool busy() const { return busy_; }

 private:
  struct Step {
    std::size_t frames = 0;
    Duration length{};
  };

  const unsigned above_;
  SteadyTime since_;
  std::size_t counted_ = 0;
  std::array<Step, kSteps> steps_{};
  std::size_t next_ = 0;
  std::size_t filled_ = 0;
  bool busy_;
};

}  // namespace teejet::gateway
