#pragma once

// The one place a client checks a command before it goes to DDS: the codec encodes it exactly as
// the gateway will, so every value the gateway would refuse is refused here first. valvectl's
// command line and teejet-web's page both go through it.

#include <string>

#include "teejet/codec/messages.hpp"
#include "teejet/core/result.hpp"
#include "teejet/valve.h"

namespace teejet::client {

// The command that carries `message` (serial, command_id and origin left for the sender), or an
// Error whose reason starts with the offending field as the codec names it ("speed_percent 101
// is outside 0 to 100"): the message's own name is dropped, the caller knows what it built.
Result<ValveCommand> checked_command(const codec::ToValveMessage& message);

// A refusal of the codec or the DDS contract without the message or command name they put
// first ("manual: speed_percent 101 ..." -> "speed_percent 101 ..."); unchanged without one.
std::string without_leading_name(std::string reason);

// The codec's direction of a drive (open or close; anything else is close) and of Target Degrees.
codec::Direction drive_direction(Direction direction);
codec::TargetDirection target_direction(Direction direction);

}  // namespace teejet::client
