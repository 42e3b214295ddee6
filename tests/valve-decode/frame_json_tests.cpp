#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "teejet/candump/log_line.hpp"
#include "teejet/codec/codec.hpp"
#include "teejet/frame_json/frame_json.hpp"

namespace teejet::frame_json {
namespace {

using nlohmann::ordered_json;

codec::DecodedFrame decoded(std::string_view line) {
  const auto record = candump::parse_log_line(line);
  EXPECT_TRUE(record) << line;
  auto frame = codec::decode(record->frame);
  EXPECT_TRUE(frame) << line << ": " << (frame ? "" : frame.error().reason);
  return *frame;
}

std::vector<std::string> keys_of(const ordered_json& object) {
  std::vector<std::string> keys;
  for (const auto& member : object.items()) keys.push_back(member.key());
  return keys;
}

TEST(ValveDecodeFrameJson, FrameAloneHasDirAddrMsgFields) {
  const auto json = frame_object(decoded("(1.000000) can0 18EFD5D8#020384FFFFFFFFFF"));
  EXPECT_EQ(json.dump(),
            R"({"dir":"from_valve","addr":216,"msg":"position","fields":{"degrees":90.0}})");
}

TEST(ValveDecodeFrameJson, AddressIsTheValveSideInBothDirections) {
  EXPECT_EQ(frame_object(decoded("(1.000000) can0 18EFF7D5#1100"))["addr"], 0xF7);
  EXPECT_EQ(frame_object(decoded("(1.000000) can0 18EFD5F7#0204D2"))["addr"], 0xF7);
  EXPECT_EQ(frame_object(decoded("(1.000000) can0 18EFF7D5#1100"))["dir"], "to_valve");
}

TEST(ValveDecodeFrameJson, MessagesWithoutFieldsGetAnEmptyObject) {
  const auto json = frame_object(decoded("(1.000000) can0 18EFD8D5#00FFFFFFFFFFFFFF"));
  EXPECT_EQ(json.dump(), R"({"dir":"to_valve","addr":216,"msg":"stop","fields":{}})");
}

TEST(ValveDecodeFrameJson, FieldsKeepWireOrderAndTypes) {
  const auto json = frame_object(decoded("(1.000000) can0 18EFD5D9#0001E2400001C801"));
  EXPECT_EQ(keys_of(json["fields"]),
            (std::vector<std::string>{"part_number", "serial", "boot_mode"}));
  EXPECT_EQ(json["fields"].dump(),
            R"({"part_number":123456,"serial":"TJV000456","boot_mode":true})");
}

TEST(ValveDecodeFrameJson, TimestampNumberKeepsEveryDigit) {
  // Cases where printing a double would not give the logged text back.
  EXPECT_EQ(timestamp_json_number(1700000000, 123), "1700000000.000123");
  EXPECT_EQ(timestamp_json_number(1700000000, 193), "1700000000.000193");
  EXPECT_EQ(timestamp_json_number(1700000000, 2967), "1700000000.002967");
  EXPECT_EQ(timestamp_json_number(1700000000, 120), "1700000000.000120");
  EXPECT_EQ(timestamp_json_number(1700000000, 0), "1700000000.000000");
  EXPECT_EQ(timestamp_json_number(1, 444), "1.000444");
  EXPECT_EQ(timestamp_json_number(0, 1), "0.000001");
  EXPECT_EQ(timestamp_json_number(9999999999, 1), "9999999999.000001");
  EXPECT_EQ(timestamp_json_number(18446744073709551615u, 999999), "18446744073709551615.999999");
  EXPECT_EQ(timestamp_json_number(1, 1'000'001), "2.000001");
}

TEST(ValveDecodeFrameJson, RecordLinePutsTimeAndInterfaceFirst) {
  const auto record =
      candump::parse_log_line("(0000000007.000120) vcan0 18EFD8D5#1105FFFFFFFFFFFF");
  ASSERT_TRUE(record);
  const auto line = record_json_line(*record, *codec::decode(record->frame));
  EXPECT_EQ(line, R"({"t":7.000120,"iface":"vcan0","dir":"to_valve","addr":216,)"
                  R"("msg":"request_position","fields":{"resend_tenths":5}})");
  const auto parsed = ordered_json::parse(line);
  EXPECT_EQ(keys_of(parsed),
            (std::vector<std::string>{"t", "iface", "dir", "addr", "msg", "fields"}));
  EXPECT_DOUBLE_EQ(parsed["t"].get<double>(), 7.00012);
}

TEST(ValveDecodeFrameJson, ErrorLineEscapesTheInput) {
  EXPECT_EQ(error_json_line("bad \"thing\"", "a\\b\t\x01"),
            R"({"error":"bad \"thing\"","line":"a\\b\t\u0001"})");
}

TEST(ValveDecodeFrameJson, InvalidUtf8IsReplacedNotThrown) {
  const auto line = error_json_line("reason", "caf\xE9 \xFF");
  EXPECT_TRUE(ordered_json::accept(line)) << line;
  // A version's test character comes straight off the bus; the codec keeps it printable.
  const auto version = decoded("(1.000000) can0 18EFD5D8#010102FF0100FF");
  const auto record = candump::parse_log_line("(1.000000) can0 18EFD5D8#010102FF0100FF");
  ASSERT_TRUE(record);
  const auto text = record_json_line(*record, version);
  ASSERT_TRUE(ordered_json::accept(text)) << text;
  EXPECT_EQ(ordered_json::parse(text)["fields"]["application"], "1.02[0xFF]");
}

TEST(ValveDecodeFrameJson, GatewayFollowsTheFirstMember) {
  const auto record =
      candump::parse_log_line("(0000000007.000120) vcan0 18EFD8D5#1105FFFFFFFFFFFF");
  ASSERT_TRUE(record);
  EXPECT_EQ(record_json_line(*record, *codec::decode(record->frame), "left \"boom\""),
            R"({"t":7.000120,"gw":"left \"boom\"","iface":"vcan0","dir":"to_valve",)"
            R"("addr":216,"msg":"request_position","fields":{"resend_tenths":5}})");
  EXPECT_EQ(error_json_line("bad", "x", "gw-1"), R"({"error":"bad","gw":"gw-1","line":"x"})");
  EXPECT_EQ(error_json_line("bad", "x", ""), R"({"error":"bad","gw":"","line":"x"})");
}

TEST(ValveDecodeFrameJson, DecodeRecordPrintsWhatTheRecordsLogLinePrints) {
  for (const char* line :
       {"(1700000000.000123) can0 18EFD5D8#0000000000007B00",
        "(1700000000.000123) can0 18EFD8D5#024B0104D2", "(1700000000.000001) can1 123#AB01",
        "(0000000001.999999) can0 18EFD5D8#", "(1700000000.000123) can0 18EFD5D8#7700"}) {
    const auto record = candump::parse_log_line(line);
    ASSERT_TRUE(record) << line;
    EXPECT_EQ(decode_record(*record), decode_log_line(line)) << line;
  }
}

TEST(ValveDecodeFrameJson, MessageErrorLineNamesTheRecordedMessage) {
  EXPECT_EQ(message_error_json_line("dlc 9 is above 8", "teejet/can/frame", 17,
                                    1'700'000'000'000'123'000ULL),
            R"({"error":"dlc 9 is above 8","topic":"teejet/can/frame","sequence":17,)"
            R"("log_time":1700000000000123000})");
}

}  // namespace
}  // namespace teejet::frame_json
