#include <gtest/gtest.h>

#include "teejet/codec/codec.hpp"

namespace teejet::codec {
namespace {

TEST(Serial, FormatsAsTJVWithSixDigits) {
  EXPECT_EQ(format_serial(123456), "TJV123456");
  EXPECT_EQ(format_serial(123), "TJV000123");
  EXPECT_EQ(format_serial(0), "TJV000000");
  EXPECT_EQ(format_serial(0xFFFFFF), "TJV16777215");  // 24 bits can exceed six digits
}

TEST(Serial, ParsesWithOrWithoutPrefix) {
  EXPECT_EQ(*parse_serial("TJV123456"), 123456u);
  EXPECT_EQ(*parse_serial("tjv000123"), 123u);
  EXPECT_EQ(*parse_serial("123456"), 123456u);
  EXPECT_EQ(*parse_serial("16777215"), 16777215u);
}

TEST(Serial, RejectsWhatIsNotASerial) {
  for (const char* text : {"", "TJV", "TJV12a456", "-1", "12 34", "TJX123456", "+5"}) {
    auto serial = parse_serial(text);
    ASSERT_FALSE(serial) << text;
    EXPECT_EQ(serial.error().code, ErrorCode::kInvalidValue);
  }
  auto too_big = parse_serial("TJV16777216");
  ASSERT_FALSE(too_big);
  EXPECT_EQ(too_big.error().code, ErrorCode::kOutOfRange);
  EXPECT_EQ(too_big.error().reason, "serial 'TJV16777216' does not fit the 24 bits of I'm Here");
}

TEST(Version, SheetExample) {
  EXPECT_EQ(format_version({1, 2, 'e'}), "1.02e");
  EXPECT_EQ(format_version({1, 2, 0}), "1.02");
  EXPECT_EQ(format_version({12, 345 % 256, 'b'}), "12.89b");
  EXPECT_EQ(format_version({1, 2, static_cast<char>(0x80)}), "1.02[0x80]");
  EXPECT_EQ(format_version({1, 2, ' '}), "1.02[0x20]");
}

TEST(Names, EnumsAndErrors) {
  EXPECT_EQ(to_string(Direction::kOpen), "open");
  EXPECT_EQ(to_string(Direction::kClose), "close");
  EXPECT_EQ(to_string(TargetDirection::kShortest), "shortest");
  EXPECT_EQ(to_string(Rotation::kClockwise), "clockwise");
  EXPECT_EQ(to_string(Rotation::kCounterclockwise), "counterclockwise");
  EXPECT_EQ(to_string(BaudAction::kSet), "set");
  EXPECT_EQ(to_string(BaudAction::kRequest), "request");
  EXPECT_EQ(to_string(static_cast<Direction>(9)), "invalid");
  EXPECT_STREQ(to_string(Flow::kToValve), "to_valve");
  EXPECT_STREQ(to_string(Flow::kFromValve), "from_valve");
  EXPECT_STREQ(to_string(ErrorCode::kTooShort), "too short");
}

}  // namespace
}  // namespace teejet::codec
