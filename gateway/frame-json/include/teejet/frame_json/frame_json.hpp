#pragma once

// JSON Lines rendering of decoded valve frames, as printed by valve-decode.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

#include "teejet/candump/log_line.hpp"
#include "teejet/codec/codec.hpp"

namespace teejet::frame_json {

// The frame alone, for tools that put their own context around it:
//   {"dir":"from_valve","addr":216,"msg":"position","fields":{"degrees":90.0}}
// "addr" is the valve's address whichever way the frame goes; "fields" is {} for messages
// without fields.
nlohmann::ordered_json frame_object(const codec::DecodedFrame& frame);

// A candump timestamp as a JSON number with exactly the logged digits: 7 -> "1700000000.000007".
// Written as text because no double prints back every microsecond timestamp digit for digit
// (nlohmann gives 1700000000.0001931 for 1700000000.000193 and drops trailing zeros).
std::string timestamp_json_number(std::uint64_t seconds, std::uint32_t microseconds);

// One output line, without the newline:
//   {"t":1700000000.000123,"iface":"can0", followed by the members of frame_json}
// With a gateway (MCAP recordings of several gateways), "gw":"<gateway>" follows "t".
std::string record_json_line(const candump::LogRecord& record, const codec::DecodedFrame& frame,
                             std::optional<std::string_view> gateway = std::nullopt);

// {"error":"<reason>","line":"<line>"}, without the newline; with a gateway,
// {"error":"<reason>","gw":"<gateway>","line":"<line>"}.
std::string error_json_line(std::string_view reason, std::string_view line,
                            std::optional<std::string_view> gateway = std::nullopt);

// A frame that was not read from a log line (an MCAP recording's teejet/can/frame sample) as
// valve-decode prints the same frame read from its candump -L line: the record, or the error
// with the candump line that the frame would have been logged as.
std::string decode_record(const candump::LogRecord& record,
                          std::optional<std::string_view> gateway = std::nullopt);

// A recorded message that is not a frame at all (does not deserialize, dlc above 8, ...):
//   {"error":"<reason>","topic":"teejet/can/frame","sequence":17,"log_time":1700000000000123000}
std::string message_error_json_line(std::string_view reason, std::string_view topic,
                                    std::uint32_t sequence, std::uint64_t log_time);

// One line of a candump -L log (without its newline) as valve-decode prints it: the record, or
// the error saying why it could not be read or decoded.
std::string decode_log_line(std::string_view line);

// Lines of spaces, tabs and carriage returns only: skipped, not reported.
bool is_blank_line(std::string_view line);

}  // namespace teejet::frame_json
