#pragma once

// The one place a client builds and checks a command before it goes to DDS: the codec sets each
// field and encodes the message exactly as the gateway will, so every value the gateway would
// refuse is refused here first, naming the field (Error::field and Error::complaint). valvectl's
// command line and teejet-web's page both go through it.

#include <string_view>
#include <utility>
#include <vector>

#include "teejet/codec/codec.hpp"
#include "teejet/core/result.hpp"
#include "teejet/valve.h"

namespace teejet::client {

using FieldValues = std::vector<std::pair<std::string_view, codec::FieldValue>>;

// `message` with each of `fields` set from what people give (a number, a word such as "open",
// ...), in order; the first refusal is the Error.
Result<codec::ToValveMessage> with_fields(codec::ToValveMessage message, const FieldValues& fields);

// The command that carries `message` (serial, command_id and origin left for the sender), or the
// codec's Error for a value the sheet does not allow.
Result<ValveCommand> checked_command(const codec::ToValveMessage& message);

}  // namespace teejet::client
