#include "teejet/recording/frames.hpp"

#include <fastdds/rtps/common/SerializedPayload.h>

#include <cstring>

#include "teejet/candump/log_line.hpp"
#include "teejet/valvePubSubTypes.h"

namespace teejet::recording {

std::optional<std::string> candump_line(std::span<const std::uint8_t> payload) {
  eprosima::fastrtps::rtps::SerializedPayload_t serialized(
      static_cast<std::uint32_t>(payload.size()));
  if (!payload.empty()) std::memcpy(serialized.data, payload.data(), payload.size());
  serialized.length = static_cast<std::uint32_t>(payload.size());
  BusFrame sample;
  BusFramePubSubType type;
  if (payload.size() < 4 || !type.deserialize(&serialized, &sample)) return std::nullopt;
  if (sample.dlc() > codec::CanFrame::kMaxData || sample.data().size() != sample.dlc()) {
    return std::nullopt;
  }
  codec::CanFrame frame;
  frame.id = sample.id();
  frame.extended = sample.extended();
  frame.dlc = sample.dlc();
  std::copy(sample.data().begin(), sample.data().end(), frame.data.begin());
  return candump::format_log_line(sample.stamp_ns() / 1'000'000'000,
                                  static_cast<std::uint32_t>(sample.stamp_ns() / 1000 % 1'000'000),
                                  sample.can_interface().to_string(), frame);
}

}  // namespace teejet::recording
