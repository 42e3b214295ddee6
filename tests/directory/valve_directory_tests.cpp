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

// ---- Faults: a displaced valve that never comes back, two valves at one address ----------

TEST(ValveDirectory, ADisplacedValveThatNeverAnnouncesAgainGoesOfflineOnTime) {
  // Its commands must end no later than a silent valve's: the timeout runs from its last I'm Here.
  ValveDirectory directory(3s);
  (void)hear(directory, 0xD9, announce(2), 0s);
  (void)hear(directory, 0xDA, announce(3), 0s);
  (void)hear(directory, 0xD9, announce(3), 500ms);  // 2 went silent; 3 moved down
  EXPECT_EQ(directory.next_expiry(), kBoot + 3s);
  EXPECT_TRUE(directory.expire(kBoot + 3s).empty());
  const auto gone = directory.expire(kBoot + 3s + 1ms);
  ASSERT_EQ(gone.size(), 1u);
  EXPECT_EQ(gone[0].kind, ChangeKind::kWentOffline);
  EXPECT_EQ(gone[0].valve.serial, 2u);
  EXPECT_FALSE(gone[0].valve.online);
  const auto later = directory.expire(kBoot + 10s);  // 3 goes offline; 2 is not reported again
  ASSERT_EQ(later.size(), 1u);
  EXPECT_EQ(later[0].valve.serial, 3u);
}

TEST(ValveDirectory, TwoValvesAnnouncingAtOneAddressAreAConflictUntilOneMovesAway) {
  ValveDirectory directory(3s);
  (void)hear(directory, 0xD9, announce(2), 0s);
  (void)hear(directory, 0xDA, announce(3), 0s);
  // 3 claims 0xD9: a readdress as far as anyone can tell yet.
  auto changes = hear(directory, 0xD9, announce(3), 300ms);
  ASSERT_EQ(changes.size(), 2u);
  EXPECT_EQ(changes[0].kind, ChangeKind::kDisplaced);
  EXPECT_EQ(changes[1].kind, ChangeKind::kReaddressed);
  // 2 announces there again: suspected, nothing attributed to the address any more.
  changes = hear(directory, 0xD9, announce(2), 1s);
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_EQ(changes[0].kind, ChangeKind::kCameOnline);
  EXPECT_EQ(directory.contest_of(2), (Contest{0xD9, 3, 2, false}));
  EXPECT_FALSE(directory.serial_at(0xD9));
  // 3 again: confirmed, reported once for each.
  changes = hear(directory, 0xD9, announce(3), 1300ms);
  ASSERT_EQ(changes.size(), 2u);
  EXPECT_EQ(changes[0].kind, ChangeKind::kAddressConflict);
  EXPECT_EQ(changes[0].valve.serial, 3u);
  EXPECT_EQ(changes[0].other, 2u);
  EXPECT_EQ(changes[1].kind, ChangeKind::kAddressConflict);
  EXPECT_EQ(changes[1].valve.serial, 2u);
  EXPECT_EQ(changes[1].other, 3u);
  EXPECT_EQ(directory.contest_of(3), (Contest{0xD9, 3, 2, true}));
  EXPECT_TRUE(hear(directory, 0xD9, announce(2), 2s).empty());  // heartbeats: nothing new
  EXPECT_TRUE(hear(directory, 0xD9, announce(3), 2300ms).empty());
  EXPECT_EQ(directory.online_count(), 2u);
  // 3 moves away: 0xD9 is 2's again.
  changes = hear(directory, 0xDA, announce(3), 2500ms);
  ASSERT_EQ(changes.size(), 2u);
  EXPECT_EQ(changes[0].kind, ChangeKind::kConflictCleared);
  EXPECT_EQ(changes[0].valve.serial, 2u);
  EXPECT_EQ(changes[0].other, 3u);
  EXPECT_EQ(changes[1].kind, ChangeKind::kReaddressed);
  EXPECT_FALSE(directory.contest_of(2));
  EXPECT_EQ(directory.serial_at(0xD9), 2u);
  EXPECT_EQ(directory.serial_at(0xDA), 3u);
}

TEST(ValveDirectory, AConflictEndsWhenOneOfTheValvesGoesSilent) {
  ValveDirectory directory(3s);
  (void)hear(directory, 0xD9, announce(2), 0s);
  (void)hear(directory, 0xD9, announce(3), 300ms);
  (void)hear(directory, 0xD9, announce(2), 1s);
  (void)hear(directory, 0xD9, announce(3), 1300ms);
  ASSERT_TRUE(directory.contest_of(2));
  (void)hear(directory, 0xD9, announce(2), 2s);  // 3 is silent from 1.3 s on
  const auto changes = directory.expire(kBoot + 4300ms + 1ms);
  ASSERT_EQ(changes.size(), 2u);
  EXPECT_EQ(changes[0].kind, ChangeKind::kWentOffline);
  EXPECT_EQ(changes[0].valve.serial, 3u);
  EXPECT_EQ(changes[1].kind, ChangeKind::kConflictCleared);
  EXPECT_EQ(changes[1].valve.serial, 2u);
  EXPECT_EQ(directory.serial_at(0xD9), 2u);
}

TEST(ValveDirectory, AValveComingBackToItsAddressWhileTheOneThatTookItMovesOnIsNoConflict) {
  // A valve restarting: the bank re-ranks, it reclaims its address and the valve that stood in
  // moves back up a moment later. Suspected for that moment, never a conflict.
  ValveDirectory directory(3s);
  (void)hear(directory, 0xD9, announce(2), 0s);
  (void)hear(directory, 0xDA, announce(3), 0s);
  (void)hear(directory, 0xD9, announce(3), 200ms);   // 2 off, 3 moves down
  (void)hear(directory, 0xD9, announce(2), 1500ms);  // 2 back
  EXPECT_TRUE(directory.contest_of(2));
  const auto changes = hear(directory, 0xDA, announce(3), 1531ms);
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_EQ(changes[0].kind, ChangeKind::kReaddressed);
  EXPECT_FALSE(directory.contest_of(2));
  EXPECT_EQ(directory.serial_at(0xD9), 2u);
  EXPECT_EQ(directory.serial_at(0xDA), 3u);
  // After longer than the timeout it is simply a readdress: no suspicion at all.
  (void)hear(directory, 0xD9, announce(3), 5s);
  (void)hear(directory, 0xD9, announce(2), 9s);
  EXPECT_FALSE(directory.contest_of(2));
  EXPECT_EQ(directory.serial_at(0xD9), 2u);
}

}  // namespace
}  // namespace teejet::directory
