#pragma once

// Samples as a gateway publishes them, for suites that feed a valve table without DDS.

#include <cstdint>
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

}  // namespace teejet::testing
