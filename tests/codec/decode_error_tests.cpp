// Every decode failure is a typed error with a reason.

#include <gtest/gtest.h>

#include "sheet_cases.hpp"

namespace teejet::codec {
namespace {

using testing::frame_of;
using testing::SheetCase;

class TruncatedMessage : public ::testing::TestWithParam<SheetCase> {};

TEST_P(TruncatedMessage, OneByteShortIsTooShortNamingTheMessage) {
  const SheetCase& c = GetParam();
  auto bytes = c.bytes;
  bytes.pop_back();
  auto decoded = decode(frame_of(c, bytes));
  ASSERT_FALSE(decoded);
  EXPECT_EQ(decoded.error().code, ErrorCode::kTooShort);
  EXPECT_EQ(decoded.error().reason, c.name + " needs " + std::to_string(c.bytes.size()) +
                                        " bytes, got " + std::to_string(bytes.size()));
}

INSTANTIATE_TEST_SUITE_P(EveryMessage, TruncatedMessage,
                         ::testing::ValuesIn(testing::sheet_cases_with_fields()),
                         testing::case_name);

CanFrame from_valve(std::vector<std::uint8_t> bytes) {
  CanFrame frame{.id = 0x18EFD5E0};
  frame.dlc = static_cast<std::uint8_t>(bytes.size());
  std::copy(bytes.begin(), bytes.end(), frame.data.begin());
  return frame;
}

CanFrame to_valve(std::vector<std::uint8_t> bytes) {
  CanFrame frame = from_valve(std::move(bytes));
  frame.id = 0x18EFE0D5;
  return frame;
}

void expect_error(const CanFrame& frame, ErrorCode code, const std::string& reason) {
  auto decoded = decode(frame);
  ASSERT_FALSE(decoded) << "decoded a frame that should fail: " << reason;
  EXPECT_EQ(decoded.error().code, code);
  EXPECT_EQ(decoded.error().reason, reason);
}

TEST(DecodeError, NoDataBytes) {
  expect_error(from_valve({}), ErrorCode::kTooShort, "no data bytes: message id missing");
  expect_error(to_valve({}), ErrorCode::kTooShort, "no data bytes: message id missing");
}

TEST(DecodeError, UnknownMessageIdsOfEachDirection) {
  expect_error(to_valve({0x06}), ErrorCode::kUnknownMessageId, "unknown message id 0x06 to_valve");
  expect_error(to_valve({0x19, 0x00}), ErrorCode::kUnknownMessageId,
               "unknown message id 0x19 to_valve");
  expect_error(from_valve({0x0A, 0, 0, 0, 0}), ErrorCode::kUnknownMessageId,
               "unknown message id 0x0A from_valve");
  expect_error(from_valve({0x16, 0, 0}), ErrorCode::kUnknownMessageId,
               "unknown message id 0x16 from_valve");
  expect_error(from_valve({0xFF, 0xFF}), ErrorCode::kUnknownMessageId,
               "unknown message id 0xFF from_valve");
}

TEST(DecodeError, BaudRateMarkers) {
  expect_error(to_valve({0x93, 0x00, 0x00}), ErrorCode::kInvalidMarker,
               "baud_rate: action byte 0x00 is not a defined value");
  expect_error(from_valve({0x93, 0x55, 0x00}), ErrorCode::kInvalidMarker,
               "baud_rate_reply: marker byte 0x55 is not 0xA5");
}

TEST(DecodeError, UndefinedEnumerationBytes) {
  expect_error(to_valve({0x01, 0x32, 0x02}), ErrorCode::kInvalidValue,
               "manual: direction byte 0x02 is not a defined value");
  expect_error(to_valve({0x02, 0x32, 0x03, 0x00, 0x00}), ErrorCode::kInvalidValue,
               "target_degrees: direction byte 0x03 is not a defined value");
  // Shortest path exists only for Target Degrees.
  expect_error(to_valve({0x03, 0x32, 0x02, 0x00, 0x00}), ErrorCode::kInvalidValue,
               "degrees_from_position: direction byte 0x02 is not a defined value");
  expect_error(from_valve({0x07, 0x32, 0x01, 0x02}), ErrorCode::kInvalidValue,
               "speed_direction: opening_direction byte 0x02 is not a defined value");
  expect_error(from_valve({0x00, 0, 0, 0, 0, 0, 1, 0x02}), ErrorCode::kInvalidValue,
               "i_am_here: boot_mode byte 0x02 is neither 0 nor 1");
  expect_error(to_valve({0x93, 0xA5, 0x02}), ErrorCode::kInvalidValue,
               "baud_rate: bit_rate code 0x02 is neither 0 (250k) nor 1 (500k)");
  expect_error(from_valve({0x15, 0, 1, 0, 1, 0x07}), ErrorCode::kInvalidValue,
               "min_degrees_per_second_error: direction byte 0x07 is not a defined value");
}

TEST(DecodeError, RoutingErrorsComeBeforeThePayload) {
  CanFrame frame = from_valve({0x02, 0x00, 0x00});
  frame.id = 0x18EFD5C0;
  expect_error(frame, ErrorCode::kNotValveAddress,
               "address 0xC0 is outside the valve range 0xD8..0xF7");
}

}  // namespace
}  // namespace teejet::codec
