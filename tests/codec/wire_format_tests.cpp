// Every message of the sheet, both directions, against bytes worked out by hand.

#include <gtest/gtest.h>

#include <algorithm>
#include <map>

#include "sheet_cases.hpp"

namespace teejet::codec {
namespace {

using testing::frame_of;
using testing::is_to_valve;
using testing::SheetCase;

class SheetMessage : public ::testing::TestWithParam<SheetCase> {};

TEST_P(SheetMessage, EncodesToTheSheetBytesPaddedToEightWithFF) {
  const SheetCase& c = GetParam();
  auto frame = testing::encode_case(c);
  ASSERT_TRUE(frame) << frame.error().reason;
  EXPECT_EQ(frame->id, is_to_valve(c) ? 0x18EFD8D5u : 0x18EFD5D8u);
  EXPECT_TRUE(frame->extended);
  EXPECT_FALSE(frame->remote);
  ASSERT_EQ(frame->dlc, 8);
  for (std::size_t i = 0; i < 8; ++i) {
    const std::uint8_t expected = i < c.bytes.size() ? c.bytes[i] : 0xFF;
    EXPECT_EQ(frame->data[i], expected) << "byte " << i;
  }
}

TEST_P(SheetMessage, EncodesToExactLengthWhenPaddingIsOff) {
  const SheetCase& c = GetParam();
  auto frame = testing::encode_case(c, EncodeOptions{.pad_to_eight = false});
  ASSERT_TRUE(frame) << frame.error().reason;
  ASSERT_EQ(frame->dlc, c.bytes.size());
  EXPECT_TRUE(std::equal(c.bytes.begin(), c.bytes.end(), frame->data.begin()));
}

TEST_P(SheetMessage, DecodesTheSheetBytesAtExactLength) {
  const SheetCase& c = GetParam();
  auto decoded = decode(frame_of(c, c.bytes));
  ASSERT_TRUE(decoded) << decoded.error().reason;
  EXPECT_EQ(decoded->route.valve_address, 0xD8);
  EXPECT_EQ(decoded->route.flow, is_to_valve(c) ? Flow::kToValve : Flow::kFromValve);
  EXPECT_EQ(decoded->message, c.message);
}

TEST_P(SheetMessage, DecodesWithJ1939PaddingAndIgnoresTrailingBytes) {
  const SheetCase& c = GetParam();
  auto padded = c.bytes;
  padded.resize(8, 0xFF);
  auto decoded = decode(frame_of(c, padded));
  ASSERT_TRUE(decoded) << decoded.error().reason;
  EXPECT_EQ(decoded->message, c.message);
}

TEST_P(SheetMessage, HasItsPublicNameIdAndFieldsInWireOrder) {
  const SheetCase& c = GetParam();
  std::vector<std::string> names;
  std::visit(
      [&](const auto& m) {
        EXPECT_EQ(message_name(m), c.name);
        EXPECT_EQ(message_id(m), c.bytes[0]);
        for_each_field(m,
                       [&](std::string_view name, const FieldValue&) { names.emplace_back(name); });
      },
      c.message);
  EXPECT_EQ(names, c.field_names);
}

INSTANTIATE_TEST_SUITE_P(EveryMessage, SheetMessage, ::testing::ValuesIn(testing::sheet_cases()),
                         testing::case_name);

// Field values as people read them (the strings valve-decode prints).
std::map<std::string, FieldValue> fields_of(const FromValveMessage& m) {
  std::map<std::string, FieldValue> out;
  for_each_field(m,
                 [&](std::string_view name, const FieldValue& v) { out[std::string(name)] = v; });
  return out;
}
std::map<std::string, FieldValue> fields_of(const ToValveMessage& m) {
  std::map<std::string, FieldValue> out;
  for_each_field(m,
                 [&](std::string_view name, const FieldValue& v) { out[std::string(name)] = v; });
  return out;
}

TEST(FieldPresentation, IAmHereShowsSerialAsTJVAndBootModeAsBool) {
  auto fields = fields_of(IAmHere{0x012345, 123456, false});
  EXPECT_EQ(fields["serial"], FieldValue{std::string("TJV123456")});
  EXPECT_EQ(fields["part_number"], FieldValue{std::int64_t{74565}});
  EXPECT_EQ(fields["boot_mode"], FieldValue{false});
}

TEST(FieldPresentation, VersionShowsSheetExampleAs1_02e) {
  auto fields = fields_of(VersionInfo{{1, 2, 'e'}, {3, 0, 0}});
  EXPECT_EQ(fields["application"], FieldValue{std::string("1.02e")});
  EXPECT_EQ(fields["bootloader"], FieldValue{std::string("3.00")});
}

TEST(FieldPresentation, DirectionsAndRotationsAreWords) {
  auto speed = fields_of(SpeedDirection{40, Direction::kOpen, Rotation::kCounterclockwise});
  EXPECT_EQ(speed["direction"], FieldValue{std::string("open")});
  EXPECT_EQ(speed["opening_direction"], FieldValue{std::string("counterclockwise")});
  auto target = fields_of(TargetDegrees{40, TargetDirection::kShortest, 10.0});
  EXPECT_EQ(target["direction"], FieldValue{std::string("shortest")});
  EXPECT_EQ(target["degrees"], FieldValue{10.0});
  auto baud = fields_of(BaudRate{BaudAction::kSet, 500000});
  EXPECT_EQ(baud["action"], FieldValue{std::string("set")});
  EXPECT_EQ(baud["bit_rate"], FieldValue{std::int64_t{500000}});
}

TEST(FieldPresentation, ScaledValuesAreEngineeringUnits) {
  EXPECT_EQ(fields_of(Voltage{12.0})["volts"], FieldValue{12.0});
  EXPECT_EQ(fields_of(RunCurrent{1.5, 0.0})["amps"], FieldValue{1.5});
  EXPECT_EQ(fields_of(Temperature{-5, 40})["valve_c"], FieldValue{std::int64_t{-5}});
}

TEST(Decoding, OutOfSheetTelemetryIsReportedAsTheWireSaysNotRejected) {
  // A logging tool must show what is on the bus; only the encoder enforces the sheet's ranges.
  CanFrame frame{.id = 0x18EFD5D8, .dlc = 3, .data = {0x02, 0xFF, 0xFF}};
  auto decoded = decode(frame);
  ASSERT_TRUE(decoded) << decoded.error().reason;
  EXPECT_EQ(std::get<1>(decoded->message), FromValveMessage{Position{6553.5}});

  frame.data = {0x03, 0x80, 0x00};  // -128 is below the sheet's -127 but is what the byte says
  decoded = decode(frame);
  ASSERT_TRUE(decoded);
  EXPECT_EQ(std::get<1>(decoded->message), (FromValveMessage{Temperature{-128, 0}}));
}

TEST(Decoding, PayloadLevelDecodersNeedNoIdentifier) {
  const std::uint8_t position[] = {0x02, 0x04, 0xD2};
  auto from = decode_from_valve(position);
  ASSERT_TRUE(from);
  EXPECT_EQ(*from, FromValveMessage{Position{123.4}});
  // The same bytes mean Target Degrees when they go to a valve, and are too short for it.
  auto to = decode_to_valve(position);
  ASSERT_FALSE(to);
  EXPECT_EQ(to.error().code, ErrorCode::kTooShort);
}

}  // namespace
}  // namespace teejet::codec
