#pragma once

// Commands teejet-web sends (the shared builders of support/valve_commands.hpp, with teejet-web's
// origin) and the statuses a gateway answers with, for the dashboard's tests.

#include <cstdint>

#include "support/valve_commands.hpp"
#include "teejet/valve.h"

namespace teejet::web::testing {

using teejet::testing::from;
using teejet::testing::move_to;
using teejet::testing::stop;

inline constexpr const char* kOrigin = "teejet-web@host:1";

// A status of teejet-web's Target Degrees command `id` to valve `serial`.
inline CommandStatus status(std::uint32_t serial, std::uint32_t id, CommandState state) {
  CommandStatus s;
  s.serial(serial);
  s.command_id(id);
  s.origin(kOrigin);
  s.kind(COMMAND_TARGET_DEGREES);
  s.state(state);
  s.stamp_ns(1000);
  return s;
}

}  // namespace teejet::web::testing
