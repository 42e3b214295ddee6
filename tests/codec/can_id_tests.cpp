#include <gtest/gtest.h>

#include "teejet/codec/can_id.hpp"

namespace teejet::codec {
namespace {

static_assert(to_valve_id(0xD8) == 0x18EFD8D5);
static_assert(from_valve_id(0xF7) == 0x18EFD5F7);
static_assert(kValveAddressCount == 32);

CanFrame extended(std::uint32_t id) { return CanFrame{.id = id, .dlc = 1}; }

TEST(CanId, BuildsBothDirections) {
  EXPECT_EQ(to_valve_id(0xE3), 0x18EFE3D5u);
  EXPECT_EQ(from_valve_id(0xE3), 0x18EFD5E3u);
}

TEST(CanId, ValveAddressRangeIsD8ToF7) {
  EXPECT_FALSE(is_valve_address(0xD7));
  EXPECT_TRUE(is_valve_address(0xD8));
  EXPECT_TRUE(is_valve_address(0xF7));
  EXPECT_FALSE(is_valve_address(0xF8));
  EXPECT_FALSE(is_valve_address(kControllerAddress));
}

TEST(Route, ControllerToValve) {
  auto route = route_of(extended(0x18EFD8D5));
  ASSERT_TRUE(route) << route.error().reason;
  EXPECT_EQ(*route, (Route{Flow::kToValve, 0xD8}));
}

TEST(Route, ValveToController) {
  auto route = route_of(extended(0x18EFD5F7));
  ASSERT_TRUE(route) << route.error().reason;
  EXPECT_EQ(*route, (Route{Flow::kFromValve, 0xF7}));
}

struct Rejection {
  CanFrame frame;
  ErrorCode code;
  std::string reason;
};

TEST(Route, RejectsEverythingThatIsNotValveTraffic) {
  const std::vector<Rejection> rejections{
      {CanFrame{.id = 0x123, .extended = false, .dlc = 1}, ErrorCode::kNotExtendedFrame,
       "11-bit identifier 0x123 is not a valve frame"},
      {CanFrame{.id = 0x18EFD5D8, .remote = true}, ErrorCode::kNotExtendedFrame,
       "remote request frame"},
      {extended(0x18FEF100), ErrorCode::kNotThisPgn,
       "identifier 0x18FEF100 is not 0x18EFxxxx (PGN 0xEF00)"},
      {extended(0x1CEFD5D8), ErrorCode::kNotThisPgn,
       "identifier 0x1CEFD5D8 is not 0x18EFxxxx (PGN 0xEF00)"},
      {extended(0x98EFD5D8), ErrorCode::kNotThisPgn,
       "identifier 0x98EFD5D8 is not 0x18EFxxxx (PGN 0xEF00)"},
      {extended(0x18EFD6D8), ErrorCode::kNotControllerTraffic,
       "from 0xD8 to 0xD6: neither side is the controller or both are"},
      {extended(0x18EFD5D5), ErrorCode::kNotControllerTraffic,
       "from 0xD5 to 0xD5: neither side is the controller or both are"},
      {extended(0x18EFD5D7), ErrorCode::kNotValveAddress,
       "address 0xD7 is outside the valve range 0xD8..0xF7"},
      {extended(0x18EFF8D5), ErrorCode::kNotValveAddress,
       "address 0xF8 is outside the valve range 0xD8..0xF7"},
  };
  for (const auto& r : rejections) {
    auto route = route_of(r.frame);
    ASSERT_FALSE(route) << std::hex << r.frame.id;
    EXPECT_EQ(route.error().code, r.code);
    EXPECT_EQ(route.error().reason, r.reason);
  }
}

}  // namespace
}  // namespace teejet::codec
