#include "teejet/recording/frames.hpp"

#include "teejet/bus_frame/bus_frame.hpp"

namespace teejet::recording {

std::optional<std::string> candump_line(std::span<const std::uint8_t> payload) {
  auto sample = bus_frame::deserialize(payload);
  if (!sample) return std::nullopt;
  auto line = bus_frame::to_candump_line(*sample);
  if (!line) return std::nullopt;
  return std::move(*line);
}

}  // namespace teejet::recording
