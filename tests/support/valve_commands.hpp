#pragma once

// ValveCommands as the suites and test peers write them: the generated type only, so that DDS
// test programs outside GoogleTest (tests/uml/gateway/hostile_writer) use them too.

#include <cstdint>

#include "teejet/valve.h"

namespace teejet::testing {

// A command of `kind` at full speed, opening: what each kind needs beyond that is set after.
inline ValveCommand command(std::uint32_t serial, CommandKind kind) {
  ValveCommand c;
  c.serial(serial);
  c.kind(kind);
  c.speed_percent(100);
  c.direction(DIRECTION_OPEN);
  return c;
}

inline ValveCommand move_to(std::uint32_t serial, float degrees, std::uint8_t speed = 100) {
  auto c = command(serial, COMMAND_TARGET_DEGREES);
  c.speed_percent(speed);
  c.degrees(degrees);
  return c;
}

}  // namespace teejet::testing
