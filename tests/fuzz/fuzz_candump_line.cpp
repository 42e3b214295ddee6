// candump::parse_log_line, which reads every recorded trace (valve-decode, canplayer logs).
//
// Input: one line of text, any bytes.
//
// Properties: a refusal is ErrorCode::kInvalidValue with a reason; an accepted line holds a
// classic CAN frame (at most eight bytes, the identifier within its 11 or 29 bits, no error
// flag), microseconds below a million, an interface name without blanks, and reads back the
// same after format_log_line.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_input.hpp"
#include "teejet/candump/log_line.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace teejet;
  fuzz::Input input(data, size);
  const auto line = input.rest();
  const auto record = candump::parse_log_line(line);
  if (!record) {
    FUZZ_CHECK(record.error().code == ErrorCode::kInvalidValue, record.error().reason);
    FUZZ_CHECK(!record.error().reason.empty(), "a refusal without a reason");
    return 0;
  }
  const auto& frame = record->frame;
  FUZZ_CHECK(frame.dlc <= codec::CanFrame::kMaxData, "dlc " + std::to_string(frame.dlc));
  FUZZ_CHECK(frame.id <= (frame.extended ? 0x1FFFFFFFU : 0x7FFU), "identifier too wide");
  FUZZ_CHECK(record->microseconds < 1'000'000,
             "microseconds " + std::to_string(record->microseconds));
  FUZZ_CHECK(!record->interface_name.empty(), "no interface name");
  FUZZ_CHECK(std::none_of(record->interface_name.begin(), record->interface_name.end(),
                          [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }),
             "blank in the interface name");
  if (frame.remote) {
    FUZZ_CHECK(std::all_of(frame.data.begin(), frame.data.end(), [](auto b) { return b == 0; }),
               "a remote frame carries data");
  }
  // The timestamp text is kept verbatim and is what the numbers were read from.
  FUZZ_CHECK(line.find("(" + record->timestamp_text + ")") != std::string_view::npos,
             "timestamp text not from the line");

  const auto formatted = candump::format_log_line(record->seconds, record->microseconds,
                                                  record->interface_name, frame);
  const auto again = candump::parse_log_line(formatted);
  FUZZ_CHECK(again, "'" + formatted +
                        "' does not parse: " + (again ? std::string() : again.error().reason));
  FUZZ_CHECK(again->frame == frame, "'" + formatted + "' reads back another frame");
  FUZZ_CHECK(again->seconds == record->seconds && again->microseconds == record->microseconds,
             "'" + formatted + "' reads back another time");
  FUZZ_CHECK(again->interface_name == record->interface_name, formatted);
  // Formatting is canonical: the second round changes nothing.
  FUZZ_CHECK(candump::format_log_line(again->seconds, again->microseconds, again->interface_name,
                                      again->frame) == formatted,
             formatted);
  return 0;
}
