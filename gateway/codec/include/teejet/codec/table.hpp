#pragma once

// The message table as data: every message of the sheet with its id, name, fields, ranges, units
// and resolutions, which reply answers which request, and the names people use for telemetry and
// error kinds. Everything outside the codec that needs a protocol fact asks here, so that the
// table in src/message_table.hpp stays the only place the fact is written: the simulator's and
// the gateway's configuration checks, valvectl's words, the dashboard's inputs, the DDS
// conversions and docs/protocol.md's tables.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "teejet/codec/codec.hpp"

namespace teejet::codec {

enum class FieldType : std::uint8_t {
  kNumber,   // an integer or a scaled value, in `unit`, from `min` to `max` by `resolution`
  kWord,     // one of `words` ("close", "open", ...)
  kSerial,   // "TJV123456"
  kVersion,  // "1.02e"
  kFlag,     // true or false
  kMarker,   // a byte with one valid value and nothing to set (the 0xA5 of the baud-rate reply)
};

struct FieldInfo {
  std::string_view name;   // "degrees"
  std::size_t offset = 0;  // first byte in the frame's data; byte 0 is the message id
  std::size_t width = 0;   // bytes on the wire
  FieldType type = FieldType::kNumber;
  std::string_view unit;  // "°", "°/s", "°C", "V", "A", "%", "ms", "s", "0.1 s"; empty for none
  double min = 0.0;       // what encode() accepts (numbers; a bit rate's lowest)
  double max = 0.0;
  double resolution = 1.0;              // the step the wire carries: 0.1 for tenths of a degree
  std::vector<std::string_view> words;  // kWord: the defined values; a bit rate's: empty
  std::vector<double> values;           // numbers that take only these values (bit rates)
};

struct MessageInfo {
  std::uint8_t id = 0;
  std::string_view name;  // "request_position", "run_current"
  Flow flow = Flow::kToValve;
  std::vector<FieldInfo> fields;  // in wire order
  // Controller to valve: a run command replaces what the valve was doing (the sheet, note 5);
  // a request names the message that answers it.
  bool run_command = false;
  std::optional<std::uint8_t> reply;
  // What a request asks for and its reply tells: the request's name without "request_"
  // ("position", "current", "version", "baud_rate"); empty for other messages.
  std::string_view subject;
  // A request for telemetry (Request Version and the eight requests with automatic resend).
  bool telemetry_request = false;
  // Valve to controller, 0x10..0x15: the kind of error ("high_voltage"); empty otherwise.
  std::string_view error_kind;
};

// Every message of one direction, in the sheet's order.
const std::vector<MessageInfo>& message_table(Flow flow);

const MessageInfo& describe(const ToValveMessage& message);
const MessageInfo& describe(const FromValveMessage& message);
// The message of an id, every field zero; nullopt for an id the sheet does not define.
std::optional<ToValveMessage> to_valve_message(std::uint8_t id);
std::optional<FromValveMessage> from_valve_message(std::uint8_t id);
// The reply that answers a request (fields zero); nullopt for run commands.
std::optional<FromValveMessage> reply_to(const ToValveMessage& request);

// nullptr when the message has no field of that name.
const FieldInfo* find_field(const MessageInfo& message, std::string_view name);

// The subject of a request or of its reply ("position", "current", "baud_rate"); empty for run
// commands, I'm Here and errors.
std::string_view subject(const ToValveMessage& message);
std::string_view subject(const FromValveMessage& message);

// ---- Telemetry and error kinds, by name -------------------------------------------------------

// The subjects of the telemetry requests, in the sheet's order: version position temperature
// voltage current degrees_per_second speed_direction run_time cycle_counts.
const std::vector<std::string_view>& telemetry_names();
// The request for one of them, resend period 0; words as people type them are accepted too:
// '-' for '_' ("run-time") and the command line's older words "dps" and "speed".
std::optional<ToValveMessage> telemetry_request(std::string_view word);

// The error kinds, in the sheet's order: high_voltage low_voltage high_current low_current
// high_temperature min_degrees_per_second.
const std::vector<std::string_view>& error_kinds();
// The error message of a kind, fields zero; '-' for '_' and the simulator's older "min-dps" are
// accepted too.
std::optional<FromValveMessage> error_message(std::string_view kind);
// The error kind of a message; empty when it is not an error.
std::string_view error_kind(const FromValveMessage& message);

// ---- Fields by name ---------------------------------------------------------------------------

// Sets one field of `message` from a value as people give it: a number in the field's unit (an
// integer field takes whole numbers only), a word of an enumeration, "TJV123456", "1.02e", true
// or false. What encode() would refuse is refused here, as a field_error naming the field.
Status set_field(ToValveMessage& message, std::string_view field, const FieldValue& value);
Status set_field(FromValveMessage& message, std::string_view field, const FieldValue& value);

// A field's value as for_each_field() presents it; nullopt when there is no such field.
std::optional<FieldValue> field_value(const ToValveMessage& message, std::string_view field);
std::optional<FieldValue> field_value(const FromValveMessage& message, std::string_view field);

// The message as the wire carries it: every scaled value on its field's grid (the 74.59999847
// of a float is the 74.6 the valve sent), so that it prints as the valve sent it; unchanged when
// a value is outside its range.
FromValveMessage as_sent(const FromValveMessage& message);
ToValveMessage as_sent(const ToValveMessage& message);

// ---- Valve mechanics ------------------------------------------------------------------------

// Opened Degrees of a full-turn ("360-degree") valve; a valve that stops at its limits opens at
// most 340 degrees (the sheet, notes 6 and 7).
inline constexpr double kFullTurnOpenedDegrees = 360.0;
inline constexpr double kMaxLimitedOpenedDegrees = 340.0;

// Closed and Opened Degrees, which the valve is configured with (no message sets or reports
// them): OK, or why not, naming closed_degrees or opened_degrees.
Status check_valve_limits(double closed_degrees, double opened_degrees);

}  // namespace teejet::codec
