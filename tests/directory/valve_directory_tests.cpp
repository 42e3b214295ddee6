#include <gtest/gtest.h>

#include "teejet/directory/valve_directory.hpp"

namespace teejet::directory {
namespace {

using namespace std::chrono_literals;

constexpr Timestamp kStart{1'700'000'000s};  // wall clock
constexpr SteadyTime kBoot{};                // steady clock at the same instant

// An I'm Here received `after` the start, on both clocks.
std::vector<Change> hear(ValveDirectory& directory, std::uint8_t address,
                         const codec::IAmHere& message, Duration after) {
  return directory.on_i_am_here(address, message, kStart + after, kBoot + after);
}

codec::IAmHere announce(std::uint32_t serial, bool boot_mode = false) {
  return {0x012345, serial, boot_mode};
}

TEST(ValveDirectory, FirstIAmHereMakesAValveAppearOnline) {
  ValveDirectory directory;
  const auto changes = hear(directory, 0xD8, announce(123456), 0s);
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_EQ(changes[0].kind, ChangeKind::kAppeared);
  EXPECT_EQ(changes[0].valve, (ValveRecord{123456, 0xD8, true, 0x012345, false, kStart, kBoot}));
  EXPECT_EQ(directory.serial_at(0xD8), 123456u);
  EXPECT_EQ(directory.online_count(), 1u);
}

TEST(ValveDirectory, RoutineHeartbeatChangesNothingButLastSeen) {
  ValveDirectory directory;
  (void)hear(directory, 0xD8, announce(1), 0s);
  EXPECT_TRUE(hear(directory, 0xD8, announce(1), 1s).empty());
  EXPECT_EQ(directory.find(1)->last_seen, kStart + 1s);
}

TEST(ValveDirectory, ASerialThatMovesKeepsItsIdentityAndItsTelemetryFollows) {
  ValveDirectory directory;
  (void)hear(directory, 0xD8, announce(200), 0s);
  const auto changes = hear(directory, 0xD9, announce(200), 1s);
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
  (void)hear(directory, 0xD8, announce(10), 0s);
  (void)hear(directory, 0xD9, announce(20), 0s);
  // Valve 20 announces from 0xD8 first; 0xD8 now means 20 while 10 has not yet re-announced.
  (void)hear(directory, 0xD8, announce(20), 1s);
  EXPECT_EQ(directory.serial_at(0xD8), 20u);
  EXPECT_FALSE(directory.serial_at(0xD9));  // nobody has announced there since 20 left
  (void)hear(directory, 0xD9, announce(10), 1s);
  EXPECT_EQ(directory.serial_at(0xD9), 10u);
  EXPECT_EQ(directory.serial_at(0xD8), 20u);
  EXPECT_EQ(directory.find(10)->address, 0xD9);
  EXPECT_EQ(directory.find(20)->address, 0xD8);
}

TEST(ValveDirectory, AValveWhoseAddressIsTakenIsOfflineUntilItAnnouncesAgain) {
  // The simulator's (and the sheet's) reshuffle: TJV000001 joins and takes 0xD8 from TJV000002,
  // which announces itself at 0xD9 a moment later. Until then nothing may be sent to 0xD8 on
  // TJV000002's behalf: that address now reaches TJV000001.
  ValveDirectory directory;
  (void)hear(directory, 0xD8, announce(2), 0s);
  const auto taken = hear(directory, 0xD8, announce(1), 1s);
  ASSERT_EQ(taken.size(), 2u);
  EXPECT_EQ(taken[0].kind, ChangeKind::kDisplaced);
  EXPECT_EQ(taken[0].valve.serial, 2u);
  EXPECT_FALSE(taken[0].valve.online);
  EXPECT_EQ(taken[0].previous_address, 0xD8);
  EXPECT_EQ(taken[1].kind, ChangeKind::kAppeared);
  EXPECT_FALSE(directory.find(2)->online);
  EXPECT_EQ(directory.online_count(), 1u);
  EXPECT_EQ(directory.serial_at(0xD8), 1u);

  const auto moved = hear(directory, 0xD9, announce(2), 1s + 31ms);
  ASSERT_EQ(moved.size(), 2u);
  EXPECT_EQ(moved[0].kind, ChangeKind::kReaddressed);
  EXPECT_EQ(moved[1].kind, ChangeKind::kCameOnline);
  EXPECT_TRUE(directory.find(2)->online);
  EXPECT_EQ(directory.find(2)->address, 0xD9);
}

TEST(ValveDirectory, AWallClockStepChangesNoDeadline) {
  // NTP or GPS setting the date at boot moves received stamps, never the offline timeout.
  ValveDirectory directory(3s);
  (void)directory.on_i_am_here(0xD8, announce(1), kStart, kBoot);
  (void)directory.on_i_am_here(0xD8, announce(1), kStart + 1h + 1s, kBoot + 1s);
  EXPECT_EQ(directory.next_expiry(), kBoot + 4s);
  EXPECT_TRUE(directory.expire(kBoot + 4s).empty());
  EXPECT_EQ(directory.find(1)->last_seen, kStart + 1h + 1s);
}

TEST(ValveDirectory, GoesOfflineAfterTheTimeoutAndComesBack) {
  ValveDirectory directory(3s);
  (void)hear(directory, 0xE0, announce(7), 0s);
  EXPECT_EQ(directory.next_expiry(), kBoot + 3s);
  EXPECT_TRUE(directory.expire(kBoot + 3s).empty());  // exactly 3 s is still online
  const auto gone = directory.expire(kBoot + 3s + 1ms);
  ASSERT_EQ(gone.size(), 1u);
  EXPECT_EQ(gone[0].kind, ChangeKind::kWentOffline);
  EXPECT_FALSE(gone[0].valve.online);
  EXPECT_FALSE(directory.serial_at(0xE0));
  EXPECT_FALSE(directory.next_expiry());
  EXPECT_TRUE(directory.expire(kBoot + 10s).empty());  // reported once

  const auto back = hear(directory, 0xE0, announce(7), 20s);
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(back[0].kind, ChangeKind::kCameOnline);
  EXPECT_EQ(directory.serial_at(0xE0), 7u);
}

TEST(ValveDirectory, ComingBackAtAnotherAddressReportsBoth) {
  ValveDirectory directory(3s);
  (void)hear(directory, 0xE0, announce(7), 0s);
  (void)directory.expire(kBoot + 5s);
  const auto back = hear(directory, 0xE1, announce(7), 6s);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0].kind, ChangeKind::kReaddressed);
  EXPECT_EQ(back[1].kind, ChangeKind::kCameOnline);
}

TEST(ValveDirectory, BootModeChangeIsReported) {
  ValveDirectory directory;
  (void)hear(directory, 0xD8, announce(5), 0s);
  const auto changes = hear(directory, 0xD8, announce(5, true), 1s);
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_EQ(changes[0].kind, ChangeKind::kModeChanged);
  EXPECT_TRUE(changes[0].valve.boot_mode);
}

TEST(ValveDirectory, ValvesAreListedBySerial) {
  ValveDirectory directory;
  (void)hear(directory, 0xDA, announce(30), 0s);
  (void)hear(directory, 0xD8, announce(10), 0s);
  (void)hear(directory, 0xD9, announce(20), 0s);
  const auto valves = directory.valves();
  ASSERT_EQ(valves.size(), 3u);
  EXPECT_EQ(valves[0].serial, 10u);
  EXPECT_EQ(valves[2].serial, 30u);
}

}  // namespace
}  // namespace teejet::directory
