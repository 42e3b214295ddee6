#pragma once

// Waiting for something another thread or process does, without a fixed sleep.

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <functional>
#include <thread>

namespace teejet::testing {

// `deadline` times TEEJET_DEADLINE_SCALE where that is set (a whole number; tools/test sets it
// for every test, the user-mode-linux tests through their own cache variable;
// tests/support/waiting.py and tools/lib/eventually.sh read the same): a deadline only bounds how
// long a failure takes to show, and a loaded host slows UML and a sanitizer build several times
// over.
template <class Rep, class Period>
std::chrono::duration<Rep, Period> scaled(std::chrono::duration<Rep, Period> deadline) {
  const char* scale = std::getenv("TEEJET_DEADLINE_SCALE");
  return deadline * (scale != nullptr ? std::max(1L, std::strtol(scale, nullptr, 10)) : 1L);
}

// Polls `condition` until it holds or `deadline` (counted from now, scaled()) passes; true if
// it held. The condition is checked once more at the deadline.
inline bool eventually(const std::function<bool()>& condition, std::chrono::milliseconds deadline) {
  const auto until = std::chrono::steady_clock::now() + scaled(deadline);
  while (std::chrono::steady_clock::now() < until) {
    if (condition()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return condition();
}

}  // namespace teejet::testing
