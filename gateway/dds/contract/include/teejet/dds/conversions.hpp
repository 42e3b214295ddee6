#pragma once

// What the DDS types of idl/ mean on the wire: telemetry frames to samples, commands to protocol
// messages and back. Pure conversions, no DDS entities, no I/O. The numeric ranges are the
// codec's (codec::encode names the field and the range); these functions refuse only what the
// IDL can express but the sheet cannot.

#include <cstdint>
#include <optional>
#include <variant>

#include "teejet/codec/codec.hpp"
#include "teejet/core/result.hpp"
#include "teejet/core/time.hpp"
#include "teejet/valve.h"

namespace teejet::dds {

// Every telemetry type a valve's message can become, each published on its own topic.
using TelemetrySample = std::variant<ValveVersion, ValvePosition, ValveTemperature, ValveVoltage,
                                     ValveCurrent, ValveDegreesPerSecond, ValveSpeedDirection,
                                     ValveRunTime, ValveCycleCount, ValveBaudRate, ValveError>;

// The sample a valve's message becomes, stamped with the CAN receive time; nullopt for I'm
// Here, which feeds the directory.
std::optional<TelemetrySample> to_sample(std::uint32_t serial,
                                         const codec::FromValveMessage& message,
                                         Timestamp received);

// The protocol message a command asks for. Refuses SHORTEST outside Target Degrees, a resend
// period for Version, and kinds, directions or telemetry the IDL does not define.
Result<codec::ToValveMessage> to_message(const ValveCommand& command);

// The command that asks for `message`: kind and fields set, serial, command_id and origin left
// for the sender. to_message(to_command(m)) == m for every message a command can carry.
ValveCommand to_command(const codec::ToValveMessage& message);

}  // namespace teejet::dds
