#include "teejet/candump/log_line.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cstddef>
#include <cstdio>
#include <optional>
#include <utility>

namespace teejet::candump {
namespace {

using codec::CanFrame;

// Linux <linux/can.h> values, spelled out so that this library builds without kernel headers.
constexpr std::uint32_t kErrorFrameFlag = 0x20000000;  // CAN_ERR_FLAG
constexpr std::uint32_t kMaxExtendedId = 0x1FFFFFFF;   // CAN_EFF_MASK
constexpr std::uint32_t kMaxStandardId = 0x7FF;        // CAN_SFF_MASK

constexpr std::size_t kExtendedIdDigits = 8;
constexpr std::size_t kStandardIdDigits = 3;
constexpr std::size_t kMicrosecondDigits = 6;
constexpr std::uint32_t kMicrosecondsPerSecond = 1'000'000;

Error malformed(std::string reason) { return Error{ErrorCode::kInvalidValue, std::move(reason)}; }

// Built by appending: GCC 12 reports a false -Wrestrict on "'" + std::string(text) at -O3.
std::string quoted(std::string_view text) {
  std::string out;
  out.reserve(text.size() + 2);
  out += '\'';
  out += text;
  out += '\'';
  return out;
}

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

bool is_decimal(char c) { return c >= '0' && c <= '9'; }

std::optional<std::uint8_t> hex_digit_value(char c) {
  if (c >= '0' && c <= '9') return static_cast<std::uint8_t>(c - '0');
  if (c >= 'A' && c <= 'F') return static_cast<std::uint8_t>(c - 'A' + 10);
  if (c >= 'a' && c <= 'f') return static_cast<std::uint8_t>(c - 'a' + 10);
  return std::nullopt;
}

bool all_hex(std::string_view text) {
  return std::all_of(text.begin(), text.end(),
                     [](char c) { return hex_digit_value(c).has_value(); });
}

void skip_blanks(std::string_view& text) {
  while (!text.empty() && is_blank(text.front())) text.remove_prefix(1);
}

// Splits off the next blank-separated word; empty when only blanks are left.
std::string_view take_word(std::string_view& text) {
  skip_blanks(text);
  const auto end = std::find_if(text.begin(), text.end(), is_blank);
  const auto word = text.substr(0, static_cast<std::size_t>(end - text.begin()));
  text.remove_prefix(word.size());
  return word;
}

std::string hex_text(std::uint32_t value, std::size_t digits) {
  static constexpr std::array<char, 16> kDigits{'0', '1', '2', '3', '4', '5', '6', '7',
                                                '8', '9', 'A', 'B', 'C', 'D', 'E', 'F'};
  std::string text(digits, '0');
  for (std::size_t i = digits; i-- > 0; value >>= 4) text[i] = kDigits[value & 0xF];
  return text;
}

struct Timestamp {
  std::uint64_t seconds;
  std::uint32_t microseconds;
};

std::optional<Timestamp> parse_timestamp(std::string_view text) {
  const auto dot = text.find('.');
  if (dot == std::string_view::npos) return std::nullopt;
  const auto seconds_text = text.substr(0, dot);
  const auto micros_text = text.substr(dot + 1);
  const auto all_decimal = [](std::string_view digits) {
    return !digits.empty() && std::all_of(digits.begin(), digits.end(), is_decimal);
  };
  if (!all_decimal(seconds_text) || !all_decimal(micros_text) ||
      micros_text.size() != kMicrosecondDigits) {
    return std::nullopt;
  }
  Timestamp stamp{};
  const auto seconds_end = seconds_text.data() + seconds_text.size();
  if (std::from_chars(seconds_text.data(), seconds_end, stamp.seconds).ec != std::errc()) {
    return std::nullopt;  // more seconds than 64 bits hold
  }
  std::from_chars(micros_text.data(), micros_text.data() + micros_text.size(), stamp.microseconds);
  return stamp;
}

// Fills id and extended from the digits before '#'.
std::optional<Error> parse_identifier(std::string_view digits, CanFrame& frame) {
  if (digits.empty() || !all_hex(digits)) {
    return malformed("identifier " + quoted(digits) + " is not hexadecimal");
  }
  if (digits.size() != kStandardIdDigits && digits.size() != kExtendedIdDigits) {
    return malformed("identifier " + quoted(digits) + " has " + std::to_string(digits.size()) +
                     " hex digits; expected 3 (11-bit) or 8 (29-bit)");
  }
  std::uint32_t id = 0;
  for (const char c : digits) id = id << 4 | *hex_digit_value(c);
  frame.extended = digits.size() == kExtendedIdDigits;
  if (!frame.extended && id > kMaxStandardId) {
    return malformed("11-bit identifier 0x" + hex_text(id, kStandardIdDigits) + " is above 0x7FF");
  }
  // candump prints error frames as 8-digit identifiers with CAN_ERR_FLAG set; they report bus
  // problems, not traffic, so they must not pass for an ordinary 29-bit frame.
  if (frame.extended && (id & kErrorFrameFlag) != 0) {
    return malformed("error frame (identifier 0x" + hex_text(id, kExtendedIdDigits) +
                     " has CAN_ERR_FLAG 0x20000000 set)");
  }
  if (frame.extended && id > kMaxExtendedId) {
    return malformed("identifier 0x" + hex_text(id, kExtendedIdDigits) + " exceeds 29 bits");
  }
  frame.id = id;
  return std::nullopt;
}

// Fills remote, dlc and data from the text after '#'.
std::optional<Error> parse_payload(std::string_view text, CanFrame& frame) {
  if (!text.empty() && text.front() == '#') {
    return malformed("CAN FD frames are not part of this protocol");
  }
  if (const auto underscore = text.find('_'); underscore != std::string_view::npos) {
    return malformed("raw DLC suffix " + quoted(text.substr(underscore)) +
                     " is not supported: the valve protocol never sends a DLC above 8");
  }
  if (!text.empty() && text.front() == 'R') {
    const auto length = text.substr(1);
    frame.remote = true;
    if (length.empty()) return std::nullopt;
    if (length.size() != 1 || !is_decimal(length.front()) ||
        length.front() > '0' + static_cast<int>(CanFrame::kMaxData)) {
      return malformed("remote frame length " + quoted(length) + " is not a digit 0 to 8");
    }
    frame.dlc = static_cast<std::uint8_t>(length.front() - '0');
    return std::nullopt;
  }
  if (!all_hex(text)) return malformed("data " + quoted(text) + " is not hexadecimal");
  if (text.size() % 2 != 0) {
    return malformed("data " + quoted(text) + " has an odd number of hex digits (" +
                     std::to_string(text.size()) + ")");
  }
  const auto byte_count = text.size() / 2;
  if (byte_count > CanFrame::kMaxData) {
    return malformed("data has " + std::to_string(byte_count) +
                     " bytes; a classic CAN frame holds at most 8");
  }
  for (std::size_t i = 0; i < byte_count; ++i) {
    frame.data[i] = static_cast<std::uint8_t>(*hex_digit_value(text[2 * i]) << 4 |
                                              *hex_digit_value(text[2 * i + 1]));
  }
  frame.dlc = static_cast<std::uint8_t>(byte_count);
  return std::nullopt;
}

}  // namespace

Result<LogRecord> parse_log_line(std::string_view line) {
  std::string_view rest = line;
  skip_blanks(rest);
  if (rest.empty() || rest.front() != '(') {
    return malformed("timestamp must be in parentheses, e.g. (1700000000.000123)");
  }
  const auto close = rest.find(')');
  if (close == std::string_view::npos) return malformed("no ')' closing the timestamp");

  LogRecord record;
  const auto timestamp_text = rest.substr(1, close - 1);
  const auto timestamp = parse_timestamp(timestamp_text);
  if (!timestamp) {
    return malformed("bad timestamp " + quoted(timestamp_text) +
                     ": expected seconds, a dot and six digits of microseconds");
  }
  record.timestamp_text = timestamp_text;
  record.seconds = timestamp->seconds;
  record.microseconds = timestamp->microseconds;
  rest.remove_prefix(close + 1);

  if (!rest.empty() && !is_blank(rest.front())) {
    return malformed("no blank between the timestamp and the interface name");
  }
  const auto interface_name = take_word(rest);
  if (interface_name.empty()) return malformed("no interface name after the timestamp");
  record.interface_name = interface_name;

  const auto frame_text = take_word(rest);
  if (frame_text.empty()) return malformed("no frame after the interface name");
  const auto hash = frame_text.find('#');
  if (hash == std::string_view::npos) {
    return malformed("frame " + quoted(frame_text) + " has no '#' between identifier and data");
  }
  if (auto failure = parse_identifier(frame_text.substr(0, hash), record.frame)) {
    return *std::move(failure);
  }
  if (auto failure = parse_payload(frame_text.substr(hash + 1), record.frame)) {
    return *std::move(failure);
  }

  // `candump -L -x` appends whether the frame was received or transmitted.
  if (const auto marker = take_word(rest); !marker.empty() && marker != "R" && marker != "T") {
    return malformed("unexpected " + quoted(marker) + " after the frame");
  }
  if (const auto extra = take_word(rest); !extra.empty()) {
    return malformed("unexpected " + quoted(extra) + " after the frame");
  }
  return record;
}

std::string format_log_line(std::uint64_t seconds, std::uint32_t microseconds,
                            std::string_view interface_name, const CanFrame& frame) {
  seconds += microseconds / kMicrosecondsPerSecond;
  microseconds %= kMicrosecondsPerSecond;
  std::array<char, 48> stamp{};
  std::snprintf(stamp.data(), stamp.size(), "(%010llu.%06u) ",
                static_cast<unsigned long long>(seconds), microseconds);

  std::string line = stamp.data();
  line += interface_name;
  line += ' ';
  line += frame.extended ? hex_text(frame.id & kMaxExtendedId, kExtendedIdDigits)
                         : hex_text(frame.id & kMaxStandardId, kStandardIdDigits);
  line += '#';
  const auto length = std::min<std::size_t>(frame.dlc, CanFrame::kMaxData);
  if (frame.remote) {
    line += 'R';
    if (length > 0) line += static_cast<char>('0' + length);
    return line;
  }
  for (std::size_t i = 0; i < length; ++i) line += hex_text(frame.data[i], 2);
  return line;
}

}  // namespace teejet::candump
