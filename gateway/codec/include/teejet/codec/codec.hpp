#pragma once

// The TeeJet CAN valve protocol codec: bytes <-> typed messages, both directions, no I/O.
// Every message is described once, declaratively, in src/message_table.hpp.

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>

#include "teejet/codec/can_id.hpp"
#include "teejet/codec/frame.hpp"
#include "teejet/codec/messages.hpp"
#include "teejet/core/result.hpp"

namespace teejet::codec {

struct EncodeOptions {
  // J1939 convention: every frame carries eight bytes, unused ones 0xFF. When false the frame
  // is exactly as long as the message.
  bool pad_to_eight = true;
  std::uint8_t pad_byte = 0xFF;
};

// ---- Payload level: data bytes only, the first one being the message id ---------------------

Result<ToValveMessage> decode_to_valve(std::span<const std::uint8_t> payload);
Result<FromValveMessage> decode_from_valve(std::span<const std::uint8_t> payload);

// ---- Frame level ----------------------------------------------------------------------------

using AnyMessage = std::variant<ToValveMessage, FromValveMessage>;

struct DecodedFrame {
  Route route;
  AnyMessage message;
};

// Routes the frame by its identifier, then decodes the payload for that direction. Any DLC
// that holds the message is accepted; trailing bytes are ignored.
Result<DecodedFrame> decode(const CanFrame& frame);

// Builds the frame for a valve address in 0xD8..0xF7, refusing out-of-range values.
Result<CanFrame> encode(std::uint8_t valve_address, const ToValveMessage& message,
                        const EncodeOptions& options = {});
Result<CanFrame> encode(std::uint8_t valve_address, const FromValveMessage& message,
                        const EncodeOptions& options = {});

// ---- What a message makes the valve do, from the message table ----------------------------

// A run command (Stop, Manual, Target Degrees, Degrees from Position, Clear Errors, Milliseconds
// to Run) replaces whatever the valve was doing: it completes the last command received.
bool is_run_command(const ToValveMessage& message);

// The id of the valve-to-controller message that answers a request (Request Position 0x11 is
// answered by Position 0x02, CAN Baud Rate 0x93 by CAN Baud Rate Reply 0x93); nullopt for run
// commands.
std::optional<std::uint8_t> reply_id(const ToValveMessage& message);

// ---- Introspection, for tools that print or log messages generically ------------------------

// The message id (first data byte) and stable snake_case name, e.g. 0x02 and "position".
std::uint8_t message_id(const ToValveMessage& message);
std::uint8_t message_id(const FromValveMessage& message);
std::string_view message_name(const ToValveMessage& message);
std::string_view message_name(const FromValveMessage& message);

// A field's value as people read it: integers, engineering units, enum names ("open"),
// formatted serials ("TJV123456") and versions ("1.02e").
using FieldValue = std::variant<std::int64_t, double, bool, std::string>;
using FieldVisitor = std::function<void(std::string_view name, const FieldValue& value)>;

// Calls visit once per field in wire order; messages without fields make no call.
void for_each_field(const ToValveMessage& message, const FieldVisitor& visit);
void for_each_field(const FromValveMessage& message, const FieldVisitor& visit);

// ---- Formatting helpers shared with tools ----------------------------------------------------

// "TJV" followed by the serial, zero-padded to six digits: 123 -> "TJV000123".
std::string format_serial(std::uint32_t serial);
// A CAN source address as people read it: 0xD5 -> "0xD5".
std::string format_address(std::uint8_t address);

// Accepts "TJV123456", "tjv123456" or "123456"; the number must fit 24 bits.
Result<std::uint32_t> parse_serial(std::string_view text);

// {1, 2, 'e'} -> "1.02e"; {1, 2, 0} -> "1.02". The minor number has at least two digits; a
// test character that is not printable ASCII shows as its byte: {1, 2, 0x80} -> "1.02[0x80]".
std::string format_version(const SoftwareVersion& version);
// The inverse: "1.02e" -> {1, 2, 'e'}, "1.02" -> {1, 2, 0}; major and minor 0 to 255.
Result<SoftwareVersion> parse_version(std::string_view text);

std::string_view to_string(Direction direction);        // "open" / "close"
std::string_view to_string(TargetDirection direction);  // "open" / "close" / "shortest"
std::string_view to_string(Rotation rotation);          // "clockwise" / "counterclockwise"
std::string_view to_string(BaudAction action);          // "set" / "request"

}  // namespace teejet::codec
