#pragma once

// The raw bus in a recording: teejet/can/frame samples (teejet::BusFrame, published by a gateway
// started with --record-frames) as can-utils' `candump -L` lines.

#include <cstdint>
#include <optional>
#include <span>
#include <string>

namespace teejet::recording {

inline constexpr const char* kFrameTopic = "teejet/can/frame";

// `(1700000000.000123) can0 18EFD5D8#020384` for a BusFrame payload (CDR, as recorded);
// nullopt when it does not deserialize or claims more than eight bytes.
std::optional<std::string> candump_line(std::span<const std::uint8_t> payload);

}  // namespace teejet::recording
