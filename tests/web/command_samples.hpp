#pragma once

// A move teejet-web sends and the statuses a gateway answers with, for the dashboard's tests.

#include <cstdint>

#include "teejet/valve.h"

namespace teejet::web::testing {

// A status of teejet-web's Target Degrees command `id` to valve `serial`.
inline CommandStatus status(std::uint32_t serial, std::uint32_t id, CommandState state) {
  CommandStatus s;
  s.serial(serial);
  s.command_id(id);
  s.origin("teejet-web@host:1");
  s.kind(COMMAND_TARGET_DEGREES);
  s.state(state);
  s.stamp_ns(1000);
  return s;
}

// Target Degrees `degrees` to valve `serial`, as sent with command id `id`.
inline ValveCommand move(std::uint32_t serial, std::uint32_t id, float degrees) {
  ValveCommand c;
  c.serial(serial);
  c.command_id(id);
  c.kind(COMMAND_TARGET_DEGREES);
  c.degrees(degrees);
  return c;
}

}  // namespace teejet::web::testing
