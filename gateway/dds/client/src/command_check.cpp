#include "teejet/client/command_check.hpp"

#include "teejet/codec/can_id.hpp"
#include "teejet/codec/codec.hpp"
#include "teejet/dds/conversions.hpp"

namespace teejet::client {

Result<ValveCommand> checked_command(const codec::ToValveMessage& message) {
  // Any valve address will do: the range rules do not depend on it.
  const auto frame = codec::encode(codec::kFirstValveAddress, message);
  if (frame) return dds::to_command(message);
  Error error = frame.error();
  error.reason = without_leading_name(std::move(error.reason));
  return error;
}

std::string without_leading_name(std::string reason) {
  if (const auto after_name = reason.find(": "); after_name != std::string::npos) {
    reason.erase(0, after_name + 2);
  }
  return reason;
}

codec::Direction drive_direction(Direction direction) {
  return direction == DIRECTION_OPEN ? codec::Direction::kOpen : codec::Direction::kClose;
}

codec::TargetDirection target_direction(Direction direction) {
  switch (direction) {
    case DIRECTION_OPEN:
      return codec::TargetDirection::kOpen;
    case DIRECTION_CLOSE:
      return codec::TargetDirection::kClose;
    case DIRECTION_SHORTEST:
      break;
  }
  return codec::TargetDirection::kShortest;
}

}  // namespace teejet::client
