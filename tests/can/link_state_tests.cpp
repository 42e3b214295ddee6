// The link state machine: which transitions happen from which state, and its two timers (the
// flags check while down, the reopen backoff while gone). Time is passed in: no kernel, no clock.
#include <gtest/gtest.h>

#include <vector>

#include "link_state.hpp"

namespace teejet::can {
namespace {

using namespace std::chrono_literals;
using State = LinkState::State;

const SteadyTime kStart = SteadyTime{} + 1h;
const SteadyTime far = kStart + 1h;

// The defaults of SocketCanOptions.
LinkState link_state() { return LinkState(100ms, 500ms); }

TEST(LinkStateTest, StartsClosedWithNoTimer) {
  LinkState link = link_state();
  EXPECT_EQ(link.state(), State::kClosed);
  EXPECT_FALSE(link.faulty());
  EXPECT_FALSE(link.down(kStart));
  EXPECT_FALSE(link.up());
  EXPECT_FALSE(link.vanished(kStart));
  EXPECT_EQ(link.state(), State::kClosed);
  EXPECT_EQ(link.next_wake(far), far);
}

TEST(LinkStateTest, OpenedUpHasNoTimer) {
  LinkState link = link_state();
  link.opened(true, kStart);
  EXPECT_EQ(link.state(), State::kUp);
  EXPECT_FALSE(link.faulty());
  EXPECT_FALSE(link.check_due(far));
  EXPECT_EQ(link.next_wake(far), far);
}

TEST(LinkStateTest, OpenedDownChecksTheFlagsEvery100Ms) {
  LinkState link = link_state();
  link.opened(false, kStart);
  EXPECT_EQ(link.state(), State::kDown);
  EXPECT_TRUE(link.faulty());
  EXPECT_EQ(link.next_wake(far), kStart + 100ms);
  EXPECT_EQ(link.next_wake(kStart + 50ms), kStart + 50ms);  // an earlier deadline wins
  EXPECT_FALSE(link.check_due(kStart + 99ms));
  EXPECT_TRUE(link.check_due(kStart + 100ms));
  link.checked(kStart + 103ms);
  EXPECT_FALSE(link.check_due(kStart + 202ms));
  EXPECT_TRUE(link.check_due(kStart + 203ms));
  EXPECT_EQ(link.next_wake(far), kStart + 203ms);
}

TEST(LinkStateTest, DownOnlyFromUpAndUpOnlyFromDown) {
  LinkState link = link_state();
  link.opened(true, kStart);
  EXPECT_FALSE(link.up());  // already up: nothing to log
  EXPECT_TRUE(link.down(kStart + 1s));
  EXPECT_EQ(link.state(), State::kDown);
  EXPECT_FALSE(link.down(kStart + 2s));  // already down: the check stays scheduled from the first
  EXPECT_TRUE(link.check_due(kStart + 1s + 100ms));
  EXPECT_TRUE(link.up());
  EXPECT_EQ(link.state(), State::kUp);
  EXPECT_FALSE(link.check_due(far));
}

TEST(LinkStateTest, GoneReopensWithABackoffThatDoublesTo500Ms) {
  LinkState link = link_state();
  link.opened(true, kStart);
  EXPECT_TRUE(link.vanished(kStart));
  EXPECT_EQ(link.state(), State::kGone);
  EXPECT_TRUE(link.faulty());
  EXPECT_FALSE(link.up());  // a gone interface comes back only through a reopen
  EXPECT_FALSE(link.down(kStart));
  SteadyTime attempt = kStart;
  for (const auto backoff : {100ms, 200ms, 400ms, 500ms, 500ms}) {
    EXPECT_EQ(link.reopen_backoff(), backoff);
    EXPECT_EQ(link.next_wake(far), attempt + backoff);
    EXPECT_FALSE(link.reopen_due(attempt + backoff - 1ns));
    EXPECT_TRUE(link.reopen_due(attempt + backoff));
    attempt += backoff;
    link.reopen_failed(attempt);
  }
}

TEST(LinkStateTest, GoneFromDownToo) {
  LinkState link = link_state();
  link.opened(false, kStart);
  EXPECT_TRUE(link.vanished(kStart + 10ms));
  EXPECT_EQ(link.state(), State::kGone);
  EXPECT_FALSE(link.check_due(far));  // no socket to ask
  EXPECT_EQ(link.next_wake(far), kStart + 110ms);
}

TEST(LinkStateTest, MissingAtOpenWaitsLikeAVanishedInterface) {
  LinkState link = link_state();
  link.missing(kStart);
  EXPECT_EQ(link.state(), State::kGone);
  EXPECT_TRUE(link.faulty());
  EXPECT_FALSE(link.up());
  EXPECT_FALSE(link.vanished(kStart));  // already gone: nothing more to log
  SteadyTime attempt = kStart;
  for (const auto backoff : {100ms, 200ms, 400ms, 500ms}) {
    EXPECT_EQ(link.next_wake(far), attempt + backoff);
    EXPECT_FALSE(link.reopen_due(attempt + backoff - 1ns));
    EXPECT_TRUE(link.reopen_due(attempt + backoff));
    attempt += backoff;
    link.reopen_failed(attempt);
  }
  link.opened(true, attempt);
  EXPECT_EQ(link.state(), State::kUp);
  EXPECT_FALSE(link.faulty());
}

TEST(LinkStateTest, VanishingAgainKeepsTheBackoff) {
  LinkState link = link_state();
  link.opened(true, kStart);
  ASSERT_TRUE(link.vanished(kStart));
  link.reopen_failed(kStart + 100ms);  // next attempt at +300 ms
  EXPECT_FALSE(link.vanished(kStart + 150ms));
  EXPECT_EQ(link.reopen_backoff(), 200ms);
  EXPECT_TRUE(link.reopen_due(kStart + 300ms));
  EXPECT_FALSE(link.reopen_due(kStart + 300ms - 1ns));
}

TEST(LinkStateTest, ReopenedStartsOverAndVanishesWithTheMinimumBackoff) {
  LinkState link = link_state();
  link.opened(true, kStart);
  ASSERT_TRUE(link.vanished(kStart));
  link.reopen_failed(kStart + 100ms);
  link.reopen_failed(kStart + 300ms);
  link.opened(false, kStart + 700ms);  // back, its link still down
  EXPECT_EQ(link.state(), State::kDown);
  EXPECT_FALSE(link.reopen_due(far));
  EXPECT_TRUE(link.check_due(kStart + 800ms));
  ASSERT_TRUE(link.vanished(kStart + 1s));
  EXPECT_EQ(link.reopen_backoff(), 100ms);
  EXPECT_TRUE(link.reopen_due(kStart + 1100ms));
}

TEST(LinkStateTest, ClosedStopsEveryTimer) {
  LinkState link = link_state();
  link.opened(true, kStart);
  ASSERT_TRUE(link.vanished(kStart));
  link.closed();
  EXPECT_EQ(link.state(), State::kClosed);
  EXPECT_FALSE(link.faulty());
  EXPECT_FALSE(link.reopen_due(far));
  EXPECT_FALSE(link.vanished(kStart));
  EXPECT_EQ(link.next_wake(far), far);
}

}  // namespace
}  // namespace teejet::can
