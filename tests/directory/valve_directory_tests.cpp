#include <gtest/gtest.h>

#include "teejet/directory/valve_directory.hpp"

namespace teejet::directory {
namespace {

using namespace std::chrono_literals;

constexpr Timestamp kStart = 1'700'000'000s;

codec::IAmHere announce(std::uint32_t serial, bool boot_mode = false) {
  return {0x012345, serial, boot_mode};
}

TEST(ValveDirectory, FirstIAmHereMakesAValveAppearOnline) {
  ValveDirectory directory;
  const auto changes = directory.on_i_am_here(0xD8, announce(123456), kStart);
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_EQ(changes[0].kind, ChangeKind::kAppeared);
  EXPECT_EQ(changes[0].valve, (ValveRecord{123456, 0xD8, true, 0x012345, false, kStart}));
  EXPECT_EQ(directory.serial_at(0xD8), 123456u);
  EXPECT_EQ(directory.online_count(), 1u);
}

TEST(ValveDirectory, RoutineHeartbeatChangesNothingButLastSeen) {
  ValveDirectory directory;
  (void)directory.on_i_am_here(0xD8, announce(1), kStart);
  EXPECT_TRUE(directory.on_i_am_here(0xD8, announce(1), kStart + 1s).empty());
  EXPECT_EQ(directory.find(1)->last_seen, kStart + 1s);
}

TEST(ValveDirectory, ASerialThatMovesKeepsItsIdentityAndItsTelemetryFollows) {
  ValveDirectory directory;
  (void)directory.on_i_am_here(0xD8, announce(200), kStart);
  const auto changes = directory.on_i_am_here(0xD9, announce(200), kStart + 1s);
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_EQ(changes[0].kind, ChangeKind::kReaddressed);
  EXPECT_EQ(changes[0].previous_address, 0xD8);
  EXPECT_EQ(changes[0].valve.address, 0xD9);
  EXPECT_EQ(directory.serial_at(0xD9), 200u);
  EXPECT_FALSE(directory.serial_at(0xD8));
  EXPECT_EQ(directory.valves().size(), 1u);
}

TEST(ValveDirectory, TwoValvesSwappingAddressesStayApart) {
  // The sheet's warning: adding a valve may reshuffle every address.
  ValveDirectory directory;
  (void)directory.on_i_am_here(0xD8, announce(10), kStart);
  (void)directory.on_i_am_here(0xD9, announce(20), kStart);
  // Valve 20 announces from 0xD8 first; 0xD8 now means 20 while 10 has not yet re-announced.
  (void)directory.on_i_am_here(0xD8, announce(20), kStart + 1s);
  EXPECT_EQ(directory.serial_at(0xD8), 20u);
  EXPECT_FALSE(directory.serial_at(0xD9));  // nobody has announced there since 20 left
  (void)directory.on_i_am_here(0xD9, announce(10), kStart + 1s);
  EXPECT_EQ(directory.serial_at(0xD9), 10u);
  EXPECT_EQ(directory.serial_at(0xD8), 20u);
  EXPECT_EQ(directory.find(10)->address, 0xD9);
  EXPECT_EQ(directory.find(20)->address, 0xD8);
}

TEST(ValveDirectory, GoesOfflineAfterTheTimeoutAndComesBack) {
  ValveDirectory directory(3s);
  (void)directory.on_i_am_here(0xE0, announce(7), kStart);
  EXPECT_EQ(directory.next_expiry(), kStart + 3s);
  EXPECT_TRUE(directory.expire(kStart + 3s).empty());  // exactly 3 s is still online
  const auto gone = directory.expire(kStart + 3s + 1ms);
  ASSERT_EQ(gone.size(), 1u);
  EXPECT_EQ(gone[0].kind, ChangeKind::kWentOffline);
  EXPECT_FALSE(gone[0].valve.online);
  EXPECT_FALSE(directory.serial_at(0xE0));
  EXPECT_FALSE(directory.next_expiry());
  EXPECT_TRUE(directory.expire(kStart + 10s).empty());  // reported once

  const auto back = directory.on_i_am_here(0xE0, announce(7), kStart + 20s);
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(back[0].kind, ChangeKind::kCameOnline);
  EXPECT_EQ(directory.serial_at(0xE0), 7u);
}

TEST(ValveDirectory, ComingBackAtAnotherAddressReportsBoth) {
  ValveDirectory directory(3s);
  (void)directory.on_i_am_here(0xE0, announce(7), kStart);
  (void)directory.expire(kStart + 5s);
  const auto back = directory.on_i_am_here(0xE1, announce(7), kStart + 6s);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0].kind, ChangeKind::kReaddressed);
  EXPECT_EQ(back[1].kind, ChangeKind::kCameOnline);
}

TEST(ValveDirectory, BootModeChangeIsReported) {
  ValveDirectory directory;
  (void)directory.on_i_am_here(0xD8, announce(5), kStart);
  const auto changes = directory.on_i_am_here(0xD8, announce(5, true), kStart + 1s);
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_EQ(changes[0].kind, ChangeKind::kModeChanged);
  EXPECT_TRUE(changes[0].valve.boot_mode);
}

TEST(ValveDirectory, ValvesAreListedBySerial) {
  ValveDirectory directory;
  (void)directory.on_i_am_here(0xDA, announce(30), kStart);
  (void)directory.on_i_am_here(0xD8, announce(10), kStart);
  (void)directory.on_i_am_here(0xD9, announce(20), kStart);
  const auto valves = directory.valves();
  ASSERT_EQ(valves.size(), 3u);
  EXPECT_EQ(valves[0].serial, 10u);
  EXPECT_EQ(valves[2].serial, 30u);
}

}  // namespace
}  // namespace teejet::directory
