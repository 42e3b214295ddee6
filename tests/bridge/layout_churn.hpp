#pragma once

// The layout changes of layout_kill_tests, in the order layout_churn makes them: a six-place boom
// and eight valves, each change putting one of them somewhere (taking it from where it sat).
// The test computes the layout after each change from the same list, without the bridge.

#include <cstdint>
#include <string>

#include "teejet/layout/layout.hpp"

namespace teejet::testing::churn {

inline constexpr std::uint32_t kValves = 8;  // serials 1..8, all online

inline layout::Layout start() {
  std::vector<layout::Location> places;
  for (unsigned i = 1; i <= 6; ++i) {
    places.push_back({.name = "section-0" + std::to_string(i), .order = i, .serial = i});
  }
  return *layout::Layout::make(std::move(places), layout::Mechanics{0, 90});
}

struct Change {
  std::string location;
  std::uint32_t serial;
};

inline Change change(std::uint64_t index) {
  return {"section-0" + std::to_string(1 + index % 6),
          static_cast<std::uint32_t>(1 + (index * 5 + index / 6) % kValves)};
}

}  // namespace teejet::testing::churn
