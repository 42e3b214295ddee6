#pragma once

// ValveCommands as the suites and test peers write them: the generated type only, so that DDS
// test programs outside GoogleTest (tests/uml/gateway/hostile_writer, tests/dds/command_writer)
// use them too.

#include <cstdint>
#include <string>

#include "teejet/valve.h"

namespace teejet::testing {

// A command of `kind` opening at `speed` percent: what each kind needs beyond that is set after.
inline ValveCommand command(std::uint32_t serial, CommandKind kind, std::uint8_t speed = 100) {
  ValveCommand c;
  c.serial(serial);
  c.kind(kind);
  c.speed_percent(speed);
  c.direction(DIRECTION_OPEN);
  return c;
}

inline ValveCommand move_to(std::uint32_t serial, float degrees, std::uint8_t speed = 100) {
  auto c = command(serial, COMMAND_TARGET_DEGREES, speed);
  c.degrees(degrees);
  return c;
}

inline ValveCommand stop(std::uint32_t serial) { return command(serial, COMMAND_STOP); }

// A request of `telemetry`: answered once (resend_tenths 0), or resent every `resend_tenths`
// tenths of a second.
inline ValveCommand request(std::uint32_t serial, Telemetry telemetry,
                            std::uint8_t resend_tenths = 0) {
  auto c = command(serial, COMMAND_REQUEST);
  c.telemetry(telemetry);
  c.resend_tenths(resend_tenths);
  return c;
}

// `c` as the commander `origin` writes it, numbered `id`. (DdsPeer numbers its own commands.)
inline ValveCommand from(const std::string& origin, std::uint32_t id, ValveCommand c) {
  c.origin(origin);
  c.command_id(id);
  return c;
}

}  // namespace teejet::testing
