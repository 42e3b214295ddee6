// The encoder refuses every value outside the sheet's ranges, with a reason, and accepts the
// boundaries themselves.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "teejet/codec/codec.hpp"

namespace teejet::codec {
namespace {

constexpr std::uint8_t kValve = 0xD8;

template <class M>
void expect_accepted(const M& message) {
  auto frame = encode(kValve, message);
  EXPECT_TRUE(frame) << frame.error().reason;
}

template <class M>
std::string expect_rejected(const M& message) {
  auto frame = encode(kValve, message);
  EXPECT_FALSE(frame) << "accepted a value outside the sheet's range";
  if (frame) return {};
  EXPECT_EQ(frame.error().code, ErrorCode::kOutOfRange);
  return frame.error().reason;
}

TEST(SpeedPercent, ZeroToOneHundredInEveryDriveCommand) {
  expect_accepted(Manual{0, Direction::kOpen});
  expect_accepted(Manual{100, Direction::kOpen});
  EXPECT_EQ(expect_rejected(Manual{101, Direction::kOpen}),
            "manual: speed_percent 101 is outside 0 to 100");
  expect_rejected(TargetDegrees{101, TargetDirection::kOpen, 0.0});
  expect_rejected(DegreesFromPosition{101, Direction::kOpen, 0.0});
  expect_rejected(MillisecondsToRun{101, Direction::kOpen, 0});
  expect_accepted(SpeedDirection{100, Direction::kOpen, Rotation::kClockwise});
  expect_rejected(SpeedDirection{101, Direction::kOpen, Rotation::kClockwise});
}

TEST(Degrees, ZeroTo359Point9InTenths) {
  expect_accepted(TargetDegrees{50, TargetDirection::kOpen, 0.0});
  expect_accepted(TargetDegrees{50, TargetDirection::kOpen, 359.9});
  EXPECT_EQ(expect_rejected(TargetDegrees{50, TargetDirection::kOpen, 360.0}),
            "target_degrees: degrees 360 is outside 0 to 359.9");
  expect_rejected(TargetDegrees{50, TargetDirection::kOpen, -0.1});
  expect_rejected(DegreesFromPosition{50, Direction::kOpen, 360.0});
  expect_accepted(DegreesFromPosition{50, Direction::kOpen, 359.9});
  expect_rejected(Position{360.0});
  expect_accepted(Position{0.0});
}

TEST(Degrees, RoundToTheNearestTenthBeforeTheRangeCheck) {
  auto frame = encode(kValve, TargetDegrees{50, TargetDirection::kOpen, 359.94});
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->data[3], 0x0E);
  EXPECT_EQ(frame->data[4], 0x0F);                                     // 3599
  expect_rejected(TargetDegrees{50, TargetDirection::kOpen, 359.95});  // rounds to 360.0
  frame = encode(kValve, TargetDegrees{50, TargetDirection::kOpen, 12.34});
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->data[4], 123);
}

TEST(Degrees, NotANumberAndInfinityAreRefused) {
  expect_rejected(TargetDegrees{50, TargetDirection::kOpen, std::nan("")});
  expect_rejected(
      TargetDegrees{50, TargetDirection::kOpen, std::numeric_limits<double>::infinity()});
  expect_rejected(Voltage{-std::numeric_limits<double>::infinity()});
}

TEST(Milliseconds, ZeroTo65535) {
  expect_accepted(MillisecondsToRun{50, Direction::kClose, 0});
  expect_accepted(MillisecondsToRun{50, Direction::kClose, 65535});
  EXPECT_EQ(expect_rejected(MillisecondsToRun{50, Direction::kClose, 65536}),
            "milliseconds_to_run: milliseconds 65536 is outside 0 to 65535");
}

TEST(ResendTenths, OneByte) {
  expect_accepted(RequestPosition{0});
  expect_accepted(RequestCycleCounts{255});
  expect_rejected(RequestPosition{256});
  expect_rejected(RequestTemperature{1000});
}

TEST(Directions, OnlyDefinedValuesLeave) {
  expect_rejected(Manual{50, static_cast<Direction>(2)});
  expect_accepted(TargetDegrees{50, TargetDirection::kShortest, 10.0});
  expect_rejected(TargetDegrees{50, static_cast<TargetDirection>(3), 10.0});
  expect_rejected(SpeedDirection{50, Direction::kOpen, static_cast<Rotation>(2)});
  EXPECT_EQ(expect_rejected(BaudRate{static_cast<BaudAction>(0x00), 250000}),
            "baud_rate: action 0x00 is not a defined value");
}

TEST(BitRate, Only250kAnd500k) {
  expect_accepted(BaudRate{BaudAction::kSet, 250000});
  expect_accepted(BaudRate{BaudAction::kSet, 500000});
  EXPECT_EQ(expect_rejected(BaudRate{BaudAction::kSet, 125000}),
            "baud_rate: bit_rate 125000 is neither 250000 nor 500000");
  expect_rejected(BaudRateReply{1000000});
}

TEST(Volts, SupplyIsZeroTo16Point5ButErrorsUseTheFullField) {
  expect_accepted(Voltage{16.5});
  EXPECT_EQ(expect_rejected(Voltage{16.6}), "voltage: volts 16.6 is outside 0 to 16.5");
  expect_rejected(Voltage{-0.1});
  expect_accepted(HighVoltageError{6553.5, 16.5});
  expect_rejected(HighVoltageError{6553.6, 16.5});
  expect_rejected(LowVoltageError{8.0, -1.0});
}

TEST(Amps, HundredthsInSixteenBits) {
  expect_accepted(RunCurrent{655.35, 0.0});
  expect_rejected(RunCurrent{655.36, 0.0});
  expect_rejected(RunCurrent{0.0, -0.01});
  expect_accepted(HighCurrentError{655.35, 0.0});
  expect_rejected(LowCurrentError{0.0, 655.36});
}

TEST(Temperature, SignedForReadingsZeroTo127ForTheHighTemperatureError) {
  expect_accepted(Temperature{-127, 127});
  EXPECT_EQ(expect_rejected(Temperature{-128, 0}),
            "temperature: valve_c -128 is outside -127 to 127");
  expect_rejected(Temperature{0, 128});
  expect_accepted(HighTemperatureError{0, 127});
  expect_rejected(HighTemperatureError{-1, 100});
  expect_rejected(HighTemperatureError{90, 128});
}

TEST(DegreesPerSecond, ZeroTo359) {
  expect_accepted(DegreesPerSecond{359, Direction::kOpen});
  expect_rejected(DegreesPerSecond{360, Direction::kOpen});
  expect_accepted(MinDegreesPerSecondError{359, 359, Direction::kClose});
  expect_rejected(MinDegreesPerSecondError{10, 360, Direction::kClose});
}

TEST(IAmHere, PartAndSerialAre24Bits) {
  expect_accepted(IAmHere{0xFFFFFF, 0xFFFFFF, false});
  expect_rejected(IAmHere{0x1000000, 1, false});
  expect_rejected(IAmHere{1, 0x1000000, false});
}

TEST(Version, PartsAreBytes) {
  expect_accepted(VersionInfo{{255, 255, 'z'}, {0, 0, 0}});
  expect_rejected(VersionInfo{{256, 0, 0}, {0, 0, 0}});
  expect_rejected(VersionInfo{{0, 0, 0}, {0, 300, 0}});
}

TEST(Counters, FullThirtyTwoBits) {
  expect_accepted(RunTime{4294967295u});
  expect_accepted(CycleCounts{4294967295u});
}

TEST(ValveAddress, OnlyD8ToF7) {
  EXPECT_TRUE(encode(0xD8, Stop{}));
  EXPECT_TRUE(encode(0xF7, Stop{}));
  for (const std::uint8_t address :
       std::initializer_list<std::uint8_t>{0x00, 0xD5, 0xD7, 0xF8, 0xFF}) {
    auto frame = encode(address, Stop{});
    ASSERT_FALSE(frame) << int{address};
    EXPECT_EQ(frame.error().code, ErrorCode::kNotValveAddress);
  }
  auto frame = encode(0xF8, Position{1.0});
  ASSERT_FALSE(frame);
  EXPECT_EQ(frame.error().reason, "address 0xF8 is outside the valve range 0xD8..0xF7");
}

}  // namespace
}  // namespace teejet::codec
