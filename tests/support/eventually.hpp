#pragma once

// Waiting for something another thread or process does, without a fixed sleep.

#include <chrono>
#include <functional>
#include <thread>

namespace teejet::testing {

// Polls `condition` until it holds or `deadline` (counted from now) passes; true if it held.
// The condition is checked once more at the deadline.
inline bool eventually(const std::function<bool()>& condition, std::chrono::milliseconds deadline) {
  const auto until = std::chrono::steady_clock::now() + deadline;
  while (std::chrono::steady_clock::now() < until) {
    if (condition()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return condition();
}

}  // namespace teejet::testing
