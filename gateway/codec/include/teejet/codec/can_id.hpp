#pragma once

#include <cstdint>

#include "teejet/codec/frame.hpp"
#include "teejet/core/result.hpp"

namespace teejet::codec {

// J1939 proprietary-A PGN 0xEF00 at priority 6: 0x18EF<destination><source>.
inline constexpr std::uint32_t kIdBase = 0x18EF0000;
inline constexpr std::uint32_t kIdBaseMask = 0x1FFF0000;
inline constexpr std::uint8_t kControllerAddress = 0xD5;
inline constexpr std::uint8_t kFirstValveAddress = 0xD8;
inline constexpr std::uint8_t kLastValveAddress = 0xF7;
inline constexpr int kValveAddressCount = kLastValveAddress - kFirstValveAddress + 1;

constexpr bool is_valve_address(std::uint8_t address) {
  return address >= kFirstValveAddress && address <= kLastValveAddress;
}

// 0x18EF<valve>D5: controller to valve.
constexpr std::uint32_t to_valve_id(std::uint8_t valve_address) {
  return kIdBase | static_cast<std::uint32_t>(valve_address) << 8 | kControllerAddress;
}

// 0x18EFD5<valve>: valve to controller.
constexpr std::uint32_t from_valve_id(std::uint8_t valve_address) {
  return kIdBase | static_cast<std::uint32_t>(kControllerAddress) << 8 | valve_address;
}

enum class Flow : std::uint8_t { kToValve, kFromValve };

const char* to_string(Flow flow);  // "to_valve" / "from_valve"

// Which way a frame goes and which valve it concerns.
struct Route {
  Flow flow;
  std::uint8_t valve_address;

  friend bool operator==(const Route&, const Route&) = default;
};

// Classifies a frame by identifier and flags alone; the payload is not looked at.
Result<Route> route_of(const CanFrame& frame);

}  // namespace teejet::codec
