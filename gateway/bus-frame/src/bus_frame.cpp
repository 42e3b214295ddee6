#include "teejet/bus_frame/bus_frame.hpp"

#include <fastdds/rtps/common/SerializedPayload.h>
#include <teejet/valvePubSubTypes.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstring>
#include <exception>

namespace teejet::bus_frame {
namespace {

constexpr std::uint64_t kNanosecondsPerSecond = 1'000'000'000;
constexpr std::uint64_t kNanosecondsPerMicrosecond = 1'000;
constexpr std::uint32_t kMaxStandardId = 0x7FF;
constexpr std::uint32_t kMaxExtendedId = 0x1FFF'FFFF;

Error invalid(std::string reason) { return Error{ErrorCode::kInvalidValue, std::move(reason)}; }

std::string hex(std::uint32_t value) {
  std::array<char, 16> text{};
  std::snprintf(text.data(), text.size(), "0x%X", value);
  return text.data();
}

// candump separates fields by blanks and canplayer splits on them: such a name cannot be logged.
bool is_loggable_interface(std::string_view name) {
  return !name.empty() && std::none_of(name.begin(), name.end(), [](char c) {
    const auto byte = static_cast<unsigned char>(c);
    return byte <= ' ' || byte == 0x7F;
  });
}

}  // namespace

Timestamp split_stamp(std::uint64_t stamp_ns) {
  return {
      stamp_ns / kNanosecondsPerSecond,
      static_cast<std::uint32_t>(stamp_ns % kNanosecondsPerSecond / kNanosecondsPerMicrosecond)};
}

Result<codec::CanFrame> to_can_frame(const teejet::BusFrame& sample) {
  if (sample.dlc() > codec::CanFrame::kMaxData) {
    return invalid("dlc " + std::to_string(sample.dlc()) + " is above 8");
  }
  if (sample.remote() && !sample.data().empty()) {
    return invalid("a remote frame with " + std::to_string(sample.data().size()) +
                   " data bytes (it carries none)");
  }
  if (!sample.remote() && sample.data().size() != sample.dlc()) {
    return invalid("dlc " + std::to_string(sample.dlc()) + " but " +
                   std::to_string(sample.data().size()) + " data bytes");
  }
  const std::uint32_t max_id = sample.extended() ? kMaxExtendedId : kMaxStandardId;
  if (sample.id() > max_id) {
    return invalid("identifier " + hex(sample.id()) + " is wider than " +
                   (sample.extended() ? "29" : "11") + " bits");
  }
  if (sample.direction() != teejet::FRAME_RECEIVED && sample.direction() != teejet::FRAME_SENT) {
    return invalid("direction " + std::to_string(static_cast<std::uint32_t>(sample.direction())) +
                   " is neither FRAME_RECEIVED (0) nor FRAME_SENT (1)");
  }
  codec::CanFrame frame;
  frame.id = sample.id();
  frame.extended = sample.extended();
  frame.remote = sample.remote();
  frame.dlc = sample.dlc();
  std::copy(sample.data().begin(), sample.data().end(), frame.data.begin());
  return frame;
}

teejet::BusFrame from_can_frame(const codec::CanFrame& frame, std::string_view gateway,
                                std::string_view can_interface, teejet::FrameDirection direction,
                                std::uint64_t stamp_ns) {
  teejet::BusFrame sample;
  sample.gateway(std::string(gateway));
  sample.can_interface(std::string(can_interface));
  sample.id(frame.id);
  sample.extended(frame.extended);
  sample.remote(frame.remote);
  const auto dlc = std::min<std::size_t>(frame.dlc, codec::CanFrame::kMaxData);
  sample.dlc(static_cast<std::uint8_t>(dlc));
  if (!frame.remote) sample.data().assign(frame.data.begin(), frame.data.begin() + dlc);
  sample.direction(direction);
  sample.stamp_ns(stamp_ns);
  return sample;
}

Result<candump::LogRecord> to_log_record(const teejet::BusFrame& sample) {
  auto frame = to_can_frame(sample);
  if (!frame) return frame.error();
  const auto time = split_stamp(sample.stamp_ns());
  candump::LogRecord record;
  record.seconds = time.seconds;
  record.microseconds = time.microseconds;
  record.interface_name = sample.can_interface().to_string();
  record.frame = *frame;
  // The text candump would have written, so that a record from a recording equals the one parsed
  // from the same frame's log line.
  std::array<char, 32> text{};
  std::snprintf(text.data(), text.size(), "%010llu.%06u",
                static_cast<unsigned long long>(time.seconds), time.microseconds);
  record.timestamp_text = text.data();
  return record;
}

Result<std::string> to_candump_line(const teejet::BusFrame& sample) {
  const std::string name = sample.can_interface().to_string();
  if (!is_loggable_interface(name)) {
    return invalid(
        "interface name \"" + name +
        "\" cannot be written to a candump log (empty, or blanks or control characters)");
  }
  auto record = to_log_record(sample);
  if (!record) return record.error();
  return candump::format_log_line(record->seconds, record->microseconds, record->interface_name,
                                  record->frame);
}

std::vector<std::uint8_t> serialize(const teejet::BusFrame& sample) {
  teejet::BusFramePubSubType type;
  teejet::BusFrame copy = sample;  // serialize() takes a non-const pointer
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&copy)());
  if (!type.serialize(&copy, &payload)) return {};
  return {payload.data, payload.data + payload.length};
}

Result<teejet::BusFrame> deserialize(std::span<const std::uint8_t> payload) {
  teejet::BusFramePubSubType type;
  eprosima::fastrtps::rtps::SerializedPayload_t buffer(static_cast<std::uint32_t>(payload.size()));
  if (!payload.empty()) std::memcpy(buffer.data, payload.data(), payload.size());
  buffer.length = static_cast<std::uint32_t>(payload.size());
  teejet::BusFrame sample;
  try {
    // The generated code catches only a payload cut short; Fast CDR throws BadParamException
    // for an unknown encapsulation or a boolean that is not 0 or 1.
    if (type.deserialize(&buffer, &sample)) return sample;
  } catch (const std::exception& exception) {
    return invalid("the BusFrame sample does not deserialize: " + std::string(exception.what()));
  }
  return invalid("the BusFrame sample does not deserialize: it ends early (" +
                 std::to_string(payload.size()) + " bytes)");
}

}  // namespace teejet::bus_frame
