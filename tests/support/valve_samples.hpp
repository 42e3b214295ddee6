#pragma once

// Samples as a gateway publishes them, for suites that feed a valve table without DDS.

#include <cstdint>
#include <optional>
#include <string>

#include "teejet/valve.h"

namespace teejet::testing {

// The presence of valve `serial` at address 0xD8 + serial.
inline ValvePresence presence(std::uint32_t serial, bool online,
                              const std::string& gateway = "gw") {
  ValvePresence p;
  p.serial(serial);
  p.address(static_cast<std::uint8_t>(0xD8 + serial));
  p.online(online);
  p.gateway(gateway);
  return p;
}

// Place `name` of `gateway`'s layout, at `order`, holding `serial` (none: empty).
inline ValveLocation location(const std::string& name, const std::string& gateway,
                              std::uint16_t order, std::optional<std::uint32_t> serial,
                              LocationState state) {
  ValveLocation p;
  p.location(name);
  p.gateway(gateway);
  p.order(order);
  p.role(ROLE_SECTION);
  p.assigned(serial.has_value());
  p.serial(serial.value_or(0));
  p.state(state);
  return p;
}

}  // namespace teejet::testing
