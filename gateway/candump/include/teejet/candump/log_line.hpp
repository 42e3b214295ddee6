#pragma once

// The log line format of can-utils `candump -L` (also read by canplayer):
//
//   (1700000000.000123) can0 18EFD5D8#020384
//
// Only classic CAN data and remote frames are accepted: the valve protocol is classic CAN, so
// CAN FD lines, error frames and anything malformed are refused with a reason instead of being
// half-understood.

#include <cstdint>
#include <string>
#include <string_view>

#include "teejet/codec/frame.hpp"
#include "teejet/core/result.hpp"

namespace teejet::candump {

struct LogRecord {
  // Kept verbatim (e.g. "1700000000.000123") so that tools can echo it without going through a
  // double, which cannot hold every microsecond timestamp digit for digit.
  std::string timestamp_text;
  std::uint64_t seconds = 0;
  std::uint32_t microseconds = 0;  // 0 .. 999999
  std::string interface_name;
  codec::CanFrame frame;

  friend bool operator==(const LogRecord&, const LogRecord&) = default;
};

// Parses one line. Accepted beyond what candump writes, because hand-edited and converted logs
// contain it: lowercase hex, several blanks between fields (candump itself right-aligns
// interface names with spaces), trailing blanks or CR, an unpadded seconds part, and the
// " R"/" T" receive/transmit marker of `candump -L -x`, which is ignored.
// Refused with ErrorCode::kInvalidValue: missing parentheses, a timestamp that is not
// <seconds>.<six digits>, an identifier that is neither 3 (11-bit) nor 8 (29-bit) hex digits or
// exceeds its width, error frames (CAN_ERR_FLAG 0x20000000), CAN FD frames ("##"), an odd number
// of hex digits, more than eight data bytes, and raw DLC suffixes ("_9").
Result<LogRecord> parse_log_line(std::string_view line);

// Formats a frame exactly as `candump -L` does: seconds zero-padded to ten digits, uppercase
// hex, eight identifier digits for 29-bit and three for 11-bit frames, "#R" plus the length
// digit (when not zero) for remote frames. Microseconds of a million or more carry into the
// seconds; a dlc above eight is clamped to eight.
std::string format_log_line(std::uint64_t seconds, std::uint32_t microseconds,
                            std::string_view interface_name, const codec::CanFrame& frame);

}  // namespace teejet::candump
