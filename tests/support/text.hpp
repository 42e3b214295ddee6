#pragma once

// Checking what a program or a refusal said.

#include <cstddef>
#include <string_view>

namespace teejet::testing {

inline bool contains(std::string_view text, std::string_view part) {
  return text.find(part) != std::string_view::npos;
}

// How often `part` occurs in `text`, not overlapping.
inline std::size_t count_of(std::string_view text, std::string_view part) {
  std::size_t count = 0;
  for (auto at = text.find(part); at != std::string_view::npos;
       at = text.find(part, at + part.size())) {
    ++count;
  }
  return count;
}

}  // namespace teejet::testing
