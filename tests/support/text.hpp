#pragma once

// Checking what a program or a refusal said.

#include <string_view>

namespace teejet::testing {

inline bool contains(std::string_view text, std::string_view part) {
  return text.find(part) != std::string_view::npos;
}

}  // namespace teejet::testing
