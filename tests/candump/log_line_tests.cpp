#include <gtest/gtest.h>

#include <cstdint>
#include <initializer_list>
#include <ostream>
#include <string>
#include <vector>

#include "teejet/candump/log_line.hpp"
#include "teejet/codec/codec.hpp"

namespace teejet::candump {

// Readable failure messages: a record shows as the line it stands for.
void PrintTo(const LogRecord& record, std::ostream* out) {
  *out << "{" << record.timestamp_text << " | "
       << format_log_line(record.seconds, record.microseconds, record.interface_name, record.frame)
       << "}";
}

namespace {

using codec::CanFrame;

CanFrame extended_frame(std::uint32_t id, std::initializer_list<std::uint8_t> bytes) {
  CanFrame frame;
  frame.id = id;
  frame.extended = true;
  for (const auto byte : bytes) frame.data[frame.dlc++] = byte;
  return frame;
}

CanFrame standard_frame(std::uint32_t id, std::initializer_list<std::uint8_t> bytes) {
  auto frame = extended_frame(id, bytes);
  frame.extended = false;
  return frame;
}

CanFrame remote_frame(std::uint32_t id, bool extended, std::uint8_t dlc) {
  CanFrame frame;
  frame.id = id;
  frame.extended = extended;
  frame.remote = true;
  frame.dlc = dlc;
  return frame;
}

LogRecord parse_ok(std::string_view line) {
  auto record = parse_log_line(line);
  EXPECT_TRUE(record.ok()) << "'" << line << "': " << (record ? "" : record.error().reason);
  return record ? *record : LogRecord{};
}

CanFrame frame_of(std::string_view line) { return parse_ok(line).frame; }

// ---- Accepted forms -------------------------------------------------------------------------

TEST(LogLineParse, ExtendedDataFrame) {
  const auto record = parse_ok("(1700000000.000123) can0 18EFD5D8#020384");
  EXPECT_EQ(record.timestamp_text, "1700000000.000123");
  EXPECT_EQ(record.seconds, 1700000000u);
  EXPECT_EQ(record.microseconds, 123u);
  EXPECT_EQ(record.interface_name, "can0");
  EXPECT_EQ(record.frame, extended_frame(0x18EFD5D8, {0x02, 0x03, 0x84}));
}

TEST(LogLineParse, StandardDataFrame) {
  EXPECT_EQ(frame_of("(1700000000.000123) can0 123#DEADBEEF"),
            standard_frame(0x123, {0xDE, 0xAD, 0xBE, 0xEF}));
}

TEST(LogLineParse, IdentifierWidthComesFromTheDigitCount) {
  // Leading zeros decide: 00000123 is a 29-bit identifier that happens to be small.
  EXPECT_EQ(frame_of("(1.000000) can0 00000123#"), extended_frame(0x123, {}));
  EXPECT_EQ(frame_of("(1.000000) can0 000#"), standard_frame(0x000, {}));
  EXPECT_EQ(frame_of("(1.000000) can0 7FF#00"), standard_frame(0x7FF, {0x00}));
  EXPECT_EQ(frame_of("(1.000000) can0 1FFFFFFF#00"), extended_frame(0x1FFFFFFF, {0x00}));
}

TEST(LogLineParse, ZeroToEightDataBytes) {
  EXPECT_EQ(frame_of("(1.000000) can0 18EFD5D8#"), extended_frame(0x18EFD5D8, {}));
  EXPECT_EQ(frame_of("(1.000000) can0 18EFD5D8#0001020304050607"),
            extended_frame(0x18EFD5D8, {0, 1, 2, 3, 4, 5, 6, 7}));
}

TEST(LogLineParse, RemoteFramesWithAndWithoutLength) {
  EXPECT_EQ(frame_of("(1.000000) can0 123#R"), remote_frame(0x123, false, 0));
  EXPECT_EQ(frame_of("(1.000000) can0 123#R0"), remote_frame(0x123, false, 0));
  EXPECT_EQ(frame_of("(1.000000) can0 123#R3"), remote_frame(0x123, false, 3));
  EXPECT_EQ(frame_of("(1.000000) can0 18EFD5D8#R8"), remote_frame(0x18EFD5D8, true, 8));
}

TEST(LogLineParse, LowercaseHex) {
  EXPECT_EQ(frame_of("(1.000000) can0 18efd5d8#0a0bff"),
            extended_frame(0x18EFD5D8, {0x0A, 0x0B, 0xFF}));
}

TEST(LogLineParse, TrailingBlanksAndLineEndings) {
  const auto expected = extended_frame(0x18EFD5D8, {0x02});
  for (const char* line : {"(1.000000) can0 18EFD5D8#02\r", "(1.000000) can0 18EFD5D8#02\r\n",
                           "(1.000000) can0 18EFD5D8#02\n", "(1.000000) can0 18EFD5D8#02  \t",
                           "(1.000000) can0 18EFD5D8#02 \r\n"}) {
    EXPECT_EQ(frame_of(line), expected) << line;
  }
}

TEST(LogLineParse, SeveralBlanksBetweenFields) {
  // candump right-aligns interface names when it listens on several interfaces.
  const auto record = parse_ok("(1700000000.000123)  can0 18EFD5D8#02");
  EXPECT_EQ(record.interface_name, "can0");
  EXPECT_EQ(parse_ok("(1.000000)\tvcan10\t\t123#02").interface_name, "vcan10");
}

TEST(LogLineParse, ReceiveTransmitMarkerOfExtraInfoIsIgnored) {
  const auto expected = extended_frame(0x18EFD5D8, {0x02});
  EXPECT_EQ(frame_of("(1.000000) can0 18EFD5D8#02 R"), expected);
  EXPECT_EQ(frame_of("(1.000000) can0 18EFD5D8#02 T"), expected);
}

TEST(LogLineParse, TimestampKeepsItsTextAndSplitsIntoIntegers) {
  const auto padded = parse_ok("(0000000001.000120) can0 123#");
  EXPECT_EQ(padded.timestamp_text, "0000000001.000120");
  EXPECT_EQ(padded.seconds, 1u);
  EXPECT_EQ(padded.microseconds, 120u);

  const auto unpadded = parse_ok("(1.999999) can0 123#");
  EXPECT_EQ(unpadded.timestamp_text, "1.999999");
  EXPECT_EQ(unpadded.microseconds, 999999u);

  const auto largest = parse_ok("(18446744073709551615.000000) can0 123#");
  EXPECT_EQ(largest.seconds, 18446744073709551615u);
}

// ---- Rejections -----------------------------------------------------------------------------

struct Rejection {
  const char* line;
  const char* reason;  // must appear in the error's reason
};

void PrintTo(const Rejection& rejection, std::ostream* out) { *out << rejection.line; }

class LogLineRejects : public testing::TestWithParam<Rejection> {};

TEST_P(LogLineRejects, WithInvalidValueAndAReason) {
  const auto& [line, reason] = GetParam();
  const auto record = parse_log_line(line);
  ASSERT_FALSE(record.ok()) << line;
  EXPECT_EQ(record.error().code, ErrorCode::kInvalidValue);
  EXPECT_NE(record.error().reason.find(reason), std::string::npos)
      << "reason: " << record.error().reason;
}

INSTANTIATE_TEST_SUITE_P(
    Malformed, LogLineRejects,
    testing::Values(
        Rejection{"", "timestamp must be in parentheses"},
        Rejection{"   ", "timestamp must be in parentheses"},
        Rejection{"1700000000.000123 can0 18EFD5D8#02", "timestamp must be in parentheses"},
        Rejection{"(1700000000.000123 can0 18EFD5D8#02", "no ')' closing the timestamp"},
        Rejection{"(1700000000) can0 18EFD5D8#02", "bad timestamp '1700000000'"},
        Rejection{"(1700000000.12) can0 18EFD5D8#02", "bad timestamp"},
        Rejection{"(1700000000.1234567) can0 18EFD5D8#02", "bad timestamp"},
        Rejection{"(.000123) can0 18EFD5D8#02", "bad timestamp"},
        Rejection{"(1.) can0 18EFD5D8#02", "bad timestamp"},
        Rejection{"(-1.000123) can0 18EFD5D8#02", "bad timestamp"},
        Rejection{"(+1.000123) can0 18EFD5D8#02", "bad timestamp"},
        Rejection{"(1a.000123) can0 18EFD5D8#02", "bad timestamp"},
        Rejection{"(1.00012x) can0 18EFD5D8#02", "bad timestamp"},
        Rejection{"(1.000 123) can0 18EFD5D8#02", "bad timestamp"},
        Rejection{"(18446744073709551616.000000) can0 123#", "bad timestamp"},
        Rejection{"(1.000000)can0 18EFD5D8#02", "no blank between the timestamp"},
        Rejection{"(1.000000)", "no interface name"},
        Rejection{"(1.000000) can0", "no frame after the interface name"},
        Rejection{"(1.000000) can0 18EFD5D8", "has no '#'"},
        Rejection{"(1.000000) can0 #02", "identifier '' is not hexadecimal"},
        Rejection{"(1.000000) can0 18EFD5DX#02", "identifier '18EFD5DX' is not hexadecimal"},
        Rejection{"(1.000000) can0 0x123#02", "is not hexadecimal"},
        Rejection{"(1.000000) can0 1234#02", "has 4 hex digits; expected 3 (11-bit) or 8"},
        Rejection{"(1.000000) can0 18EFD5D#02", "has 7 hex digits"},
        Rejection{"(1.000000) can0 018EFD5D8#02", "has 9 hex digits"},
        Rejection{"(1.000000) can0 800#02", "11-bit identifier 0x800 is above 0x7FF"},
        Rejection{"(1.000000) can0 FFF#02", "11-bit identifier 0xFFF is above 0x7FF"},
        Rejection{"(1.000000) can0 20000004#0004000000000000", "error frame"},
        Rejection{"(1.000000) can0 200000FF#0000000000000000", "error frame"},
        Rejection{"(1.000000) can0 40000000#02", "identifier 0x40000000 exceeds 29 bits"},
        Rejection{"(1.000000) can0 80000123#02", "exceeds 29 bits"},
        Rejection{"(1.000000) can0 18EFD5D8##10203", "CAN FD frames are not part of this protocol"},
        Rejection{"(1.000000) can0 123##0", "CAN FD frames are not part of this protocol"},
        Rejection{"(1.000000) can0 18EFD5D8#020", "odd number of hex digits (3)"},
        Rejection{"(1.000000) can0 18EFD5D8#0", "odd number of hex digits (1)"},
        Rejection{"(1.000000) can0 18EFD5D8#000102030405060708", "9 bytes"},
        Rejection{"(1.000000) can0 18EFD5D8#00010203040506070809101112131415", "16 bytes"},
        Rejection{"(1.000000) can0 18EFD5D8#0G", "data '0G' is not hexadecimal"},
        Rejection{"(1.000000) can0 18EFD5D8#02.03", "is not hexadecimal"},
        Rejection{"(1.000000) can0 123#1122334455667788_9", "raw DLC suffix '_9'"},
        Rejection{"(1.000000) can0 123#R8_9", "raw DLC suffix"},
        Rejection{"(1.000000) can0 123#R9", "remote frame length '9' is not a digit 0 to 8"},
        Rejection{"(1.000000) can0 123#RA", "remote frame length"},
        Rejection{"(1.000000) can0 123#R12", "remote frame length"},
        Rejection{"(1.000000) can0 123#r", "is not hexadecimal"},
        Rejection{"(1.000000) can0 123#02 extra", "unexpected 'extra' after the frame"},
        Rejection{"(1.000000) can0 123#02 R extra", "unexpected 'extra' after the frame"}));

// ---- Formatting -----------------------------------------------------------------------------

TEST(LogLineFormat, ExtendedFrameAsCandumpWritesIt) {
  EXPECT_EQ(format_log_line(1700000000, 123, "can0", extended_frame(0x18EFD5D8, {2, 3, 0x84})),
            "(1700000000.000123) can0 18EFD5D8#020384");
}

TEST(LogLineFormat, PadsSecondsToTenDigitsAndIdentifiersToTheirWidth) {
  EXPECT_EQ(format_log_line(1, 2, "vcan0", standard_frame(0xA, {0x0A, 0xBC})),
            "(0000000001.000002) vcan0 00A#0ABC");
  EXPECT_EQ(format_log_line(0, 0, "can0", extended_frame(0x1, {})),
            "(0000000000.000000) can0 00000001#");
}

TEST(LogLineFormat, UppercaseHex) {
  EXPECT_EQ(format_log_line(1, 0, "can0", extended_frame(0x1abcdef0, {0xab, 0xcd})),
            "(0000000001.000000) can0 1ABCDEF0#ABCD");
}

TEST(LogLineFormat, RemoteFramesPrintTheLengthUnlessZero) {
  EXPECT_EQ(format_log_line(1, 0, "can0", remote_frame(0x123, false, 0)),
            "(0000000001.000000) can0 123#R");
  EXPECT_EQ(format_log_line(1, 0, "can0", remote_frame(0x18EFD5D8, true, 8)),
            "(0000000001.000000) can0 18EFD5D8#R8");
}

TEST(LogLineFormat, MicrosecondsCarryIntoSeconds) {
  EXPECT_EQ(format_log_line(1, 2'000'005, "can0", standard_frame(0x1, {})),
            "(0000000003.000005) can0 001#");
}

TEST(LogLineFormat, DlcAboveEightIsClampedToTheEightBytesAFrameHolds) {
  auto frame = extended_frame(0x18EFD5D8, {0, 1, 2, 3, 4, 5, 6, 7});
  frame.dlc = 15;
  EXPECT_EQ(format_log_line(1, 0, "can0", frame),
            "(0000000001.000000) can0 18EFD5D8#0001020304050607");
}

// ---- Round trips ----------------------------------------------------------------------------

TEST(LogLineRoundTrip, ParseOfFormatGivesTheRecordBack) {
  std::vector<LogRecord> records;
  const auto add = [&records](std::uint64_t seconds, std::uint32_t micros, const char* iface,
                              const CanFrame& frame) {
    LogRecord record;
    record.seconds = seconds;
    record.microseconds = micros;
    record.interface_name = iface;
    record.frame = frame;
    records.push_back(record);
  };
  add(1700000000, 123, "can0", extended_frame(0x18EFD5D8, {0x02, 0x03, 0x84}));
  add(1700000000, 999999, "can0", extended_frame(0x18EFD8D5, {}));
  add(0, 0, "vcan0", standard_frame(0x7FF, {0, 1, 2, 3, 4, 5, 6, 7}));
  add(12345678901, 1, "can1", standard_frame(0x000, {0xFF}));
  add(1, 500000, "can0", remote_frame(0x123, false, 0));
  add(1, 500000, "can0", remote_frame(0x1FFFFFFF, true, 8));
  // Every frame of the protocol as the codec builds it, both directions.
  auto to_valve = codec::encode(0xD8, codec::ToValveMessage{codec::TargetDegrees{100, {}, 90.0}});
  auto from_valve = codec::encode(0xF7, codec::FromValveMessage{codec::IAmHere{0, 123456, false}});
  ASSERT_TRUE(to_valve && from_valve);
  add(1700000000, 42, "can0", *to_valve);
  add(1700000000, 43, "can0", *from_valve);

  for (auto& record : records) {
    const auto line =
        format_log_line(record.seconds, record.microseconds, record.interface_name, record.frame);
    record.timestamp_text = line.substr(1, line.find(')') - 1);
    EXPECT_EQ(parse_ok(line), record) << line;
  }
}

TEST(LogLineRoundTrip, FormatOfParseGivesCandumpLinesBack) {
  for (const char* line :
       {"(1700000000.000123) can0 18EFD5D8#020384FFFFFFFFFF", "(1700000000.000000) can0 18EFD8D5#",
        "(0000000042.100000) vcan0 123#DEADBEEF", "(1700000000.000123) can0 123#R",
        "(1700000000.000123) can0 123#R5"}) {
    const auto record = parse_ok(line);
    EXPECT_EQ(
        format_log_line(record.seconds, record.microseconds, record.interface_name, record.frame),
        line);
  }
}

TEST(LogLineRoundTrip, ParsedFramesDecodeWithTheCodec) {
  const auto record = parse_ok("(1700000000.000123) can0 18EFD5D8#020384FFFFFFFFFF");
  const auto decoded = codec::decode(record.frame);
  ASSERT_TRUE(decoded) << decoded.error().reason;
  EXPECT_EQ(decoded->route, (codec::Route{codec::Flow::kFromValve, 0xD8}));
  EXPECT_EQ(std::get<codec::FromValveMessage>(decoded->message),
            codec::FromValveMessage{codec::Position{90.0}});
}

}  // namespace
}  // namespace teejet::candump
