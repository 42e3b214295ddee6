#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace teejet::codec {

// A classic CAN frame as the codec sees it: identifier, flags and up to eight data bytes.
struct CanFrame {
  static constexpr std::size_t kMaxData = 8;

  std::uint32_t id = 0;  // 29-bit (extended) or 11-bit identifier, without flag bits
  bool extended = true;
  bool remote = false;
  std::uint8_t dlc = 0;
  std::array<std::uint8_t, kMaxData> data{};

  std::span<const std::uint8_t> payload() const { return {data.data(), dlc}; }

  friend bool operator==(const CanFrame&, const CanFrame&) = default;
};

}  // namespace teejet::codec
