#pragma once

// Pure conversions between the protocol codec's messages and the DDS types of idl/: telemetry
// frames to samples, commands to frames. No DDS entities, no I/O.

#include <chrono>
#include <cstdint>
#include <optional>
#include <variant>

#include "teejet/codec/codec.hpp"
#include "teejet/valve.h"

namespace teejet::bridge {

using Timestamp = std::chrono::nanoseconds;  // since the Unix epoch

using TelemetrySample = std::variant<ValveVersion, ValvePosition, ValveTemperature, ValveVoltage,
                                     ValveCurrent, ValveDegreesPerSecond, ValveSpeedDirection,
                                     ValveRunTime, ValveCycleCount, ValveBaudRate, ValveError>;

// The sample a valve's message becomes; nullopt for I'm Here, which feeds the directory.
std::optional<TelemetrySample> to_sample(std::uint32_t serial,
                                         const codec::FromValveMessage& message,
                                         Timestamp received);

// The protocol message a command asks for. Refuses what the IDL can express but the sheet
// cannot (SHORTEST outside Target Degrees, a resend period for Version, an unknown kind); the
// numeric ranges are checked by codec::encode, which names the field and the range.
codec::Result<codec::ToValveMessage> to_message(const ValveCommand& command);

const char* to_string(CommandKind kind);
const char* to_string(CommandState state);

}  // namespace teejet::bridge
