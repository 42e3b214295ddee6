#pragma once

// What the DDS types of idl/ mean on the wire: telemetry frames to samples and back, commands to
// protocol messages and back. Pure conversions, no DDS entities, no I/O. Ranges, names and
// resolutions are the codec's (teejet/codec/table.hpp): what the codec refuses is refused with
// the codec's reason, naming the field; these functions refuse only what the IDL can express but
// the sheet cannot.
//
// A new telemetry message is a row here (its IDL Telemetry value and request), its sample type
// in TelemetrySample, and one overload each of to_sample and from_sample in conversions.cpp.
// Its topic, its names and every client follow from those.

#include <cstdint>
#include <optional>
#include <string_view>
#include <type_traits>
#include <variant>

#include "teejet/codec/codec.hpp"
#include "teejet/core/result.hpp"
#include "teejet/core/time.hpp"
#include "teejet/isobus/address_claimer.hpp"
#include "teejet/valve.h"

namespace teejet::dds {

// Every telemetry type a valve's message can become, each published on its own topic.
using TelemetrySample = std::variant<ValvePosition, ValveVersion, ValveTemperature, ValveVoltage,
                                     ValveCurrent, ValveDegreesPerSecond, ValveSpeedDirection,
                                     ValveRunTime, ValveCycleCounts, ValveBaudRate, ValveError>;

template <class Sample, class Variant = TelemetrySample>
inline constexpr bool kIsAlternative = false;
template <class Sample, class... Samples>
inline constexpr bool kIsAlternative<Sample, std::variant<Samples...>> =
    (std::is_same_v<Sample, Samples> || ...);

// The sample a valve's message becomes, stamped with the CAN receive time; nullopt for I'm
// Here, which feeds the directory.
std::optional<TelemetrySample> to_sample(std::uint32_t serial,
                                         const codec::FromValveMessage& message,
                                         Timestamp received);

// The valve's message a sample tells of, with every scaled value on its field's grid (the
// float 74.6f of a position is the 74.6 the valve sent), so that clients can name, range and
// print it through the codec's table. Inverse of to_sample for every telemetry message.
codec::FromValveMessage from_sample(const TelemetrySample& sample);

// The protocol message a command asks for; an Error (naming the field) for what the codec
// refuses, SHORTEST outside Target Degrees, a resend period for Version, and kinds, directions
// or telemetry the IDL does not define.
Result<codec::ToValveMessage> to_message(const ValveCommand& command);

// The command that asks for `message`: kind and fields set, serial, command_id and origin left
// for the sender. to_message(to_command(m)) == m for every message a command can carry.
ValveCommand to_command(const codec::ToValveMessage& message);

// ---- Telemetry and error kinds: the IDL's enumerations and the codec's messages ----------------

// The request a COMMAND_REQUEST of `telemetry` sends (resend period 0); nullopt for a value the
// IDL does not define.
std::optional<codec::ToValveMessage> request_of(Telemetry telemetry);
// The IDL's value for a telemetry request, or for a word as people type it ("run-time", "dps").
std::optional<Telemetry> telemetry_of(const codec::ToValveMessage& request);
std::optional<Telemetry> telemetry_of(std::string_view word);

// The error message of an ErrorKind (fields zero), and the kind of an error message.
std::optional<codec::FromValveMessage> error_message_of(ErrorKind kind);
std::optional<ErrorKind> error_kind_of(const codec::FromValveMessage& message);

// The codec's direction word of an IDL Direction ("close", "open", "shortest"); empty for a
// value the IDL does not define. The IDL's values are the wire's (Close 0, Open 1, shortest 2).
std::string_view direction_word(Direction direction);
std::optional<Direction> direction_of(std::string_view word);

// The address claim's state on the wire and back.
AddressClaimState to_idl(isobus::ClaimState state);
isobus::ClaimState from_idl(AddressClaimState state);

}  // namespace teejet::dds
