// The bounded ENOBUFS retry queue: order, bound, backoff, and what a flush does with each
// outcome of a write. Time is passed in, writes are recorded: no kernel, no clock.
#include <gtest/gtest.h>

#include <cerrno>
#include <vector>

#include "retry_queue.hpp"

namespace teejet::can {
namespace {

using namespace std::chrono_literals;

const SteadyTime t0 = SteadyTime{} + 1h;

can_frame numbered(std::uint8_t n) {
  can_frame out{};
  out.can_id = 0x98EFD8D5;
  out.len = 1;
  out.data[0] = n;
  return out;
}

// A write that answers from a script and records what it was given.
struct ScriptedWrite {
  std::vector<WriteOutcome> outcomes;  // one per call; kSent after the script ends
  int error_number = ENOBUFS;          // given with kBusy and kFailed
  std::vector<std::uint8_t> written;   // data[0] of every frame offered
  WriteOutcome operator()(const can_frame& frame, int& error) {
    written.push_back(frame.data[0]);
    const WriteOutcome outcome =
        written.size() <= outcomes.size() ? outcomes[written.size() - 1] : WriteOutcome::kSent;
    if (outcome != WriteOutcome::kSent) error = error_number;
    return outcome;
  }
};

TEST(RetryQueueTest, BoundedAndInOrder) {
  RetryQueue queue(3);
  EXPECT_TRUE(queue.empty());
  for (std::uint8_t n = 0; n < 3; ++n) EXPECT_TRUE(queue.push(numbered(n)));
  EXPECT_FALSE(queue.push(numbered(3)));
  EXPECT_EQ(queue.size(), 3u);
  ScriptedWrite write;
  const auto flushed = queue.flush(t0, std::ref(write));
  EXPECT_EQ(flushed.retried, 3u);
  EXPECT_EQ(flushed.failed, 0u);
  EXPECT_EQ(write.written, (std::vector<std::uint8_t>{0, 1, 2}));
  EXPECT_TRUE(queue.empty());
}

TEST(RetryQueueTest, EnobufsRetriesOnATimerThatDoublesTo64Ms) {
  RetryQueue queue(8);
  ASSERT_TRUE(queue.push(numbered(0)));
  SteadyTime now = t0;
  for (const auto expected : {2ms, 4ms, 8ms, 16ms, 32ms, 64ms, 64ms}) {
    queue.refused(ENOBUFS, now);
    EXPECT_FALSE(queue.waits_for_pollout());
    EXPECT_EQ(queue.retry_at(), now + expected);
    EXPECT_FALSE(queue.due(now + expected - 1ns));
    EXPECT_TRUE(queue.due(now + expected));
    now += expected;
  }
  queue.restart_backoff();
  queue.refused(ENOBUFS, now);
  EXPECT_EQ(queue.retry_at(), now + 2ms);
}

TEST(RetryQueueTest, EagainWaitsForPolloutNotTheTimer) {
  RetryQueue queue(8);
  ASSERT_TRUE(queue.push(numbered(0)));
  queue.refused(EAGAIN, t0);
  EXPECT_TRUE(queue.waits_for_pollout());
  EXPECT_FALSE(queue.due(t0 + 1h));
  queue.refused(ENOBUFS, t0);  // the next refusal decides again
  EXPECT_FALSE(queue.waits_for_pollout());
  EXPECT_TRUE(queue.due(t0 + 4ms));  // the backoff kept doubling: 2, then 4 ms
  EXPECT_FALSE(queue.due(t0 + 4ms - 1ns));
}

TEST(RetryQueueTest, AnEmptyQueueIsNeverDue) {
  RetryQueue queue(8);
  queue.refused(ENOBUFS, t0);
  EXPECT_FALSE(queue.due(t0 + 1h));
  queue.refused(EAGAIN, t0);
  EXPECT_FALSE(queue.waits_for_pollout());
}

TEST(RetryQueueTest, FlushStopsWhenTheKernelRefusesAgain) {
  RetryQueue queue(8);
  for (std::uint8_t n = 0; n < 5; ++n) ASSERT_TRUE(queue.push(numbered(n)));
  ScriptedWrite write{.outcomes = {WriteOutcome::kSent, WriteOutcome::kSent, WriteOutcome::kBusy}};
  const auto flushed = queue.flush(t0, std::ref(write));
  EXPECT_EQ(flushed.retried, 2u);
  EXPECT_EQ(flushed.failed, 0u);
  EXPECT_EQ(write.written, (std::vector<std::uint8_t>{0, 1, 2}));
  EXPECT_EQ(queue.size(), 3u);  // 2, 3, 4: the refused frame stays first
  EXPECT_EQ(queue.retry_at(), t0 + 2ms);

  ScriptedWrite rest;
  EXPECT_EQ(queue.flush(t0 + 2ms, std::ref(rest)).retried, 3u);
  EXPECT_EQ(rest.written, (std::vector<std::uint8_t>{2, 3, 4}));
}

TEST(RetryQueueTest, AFrameRefusedForGoodIsDroppedAndTheRestGoOn) {
  RetryQueue queue(8);
  for (std::uint8_t n = 0; n < 3; ++n) ASSERT_TRUE(queue.push(numbered(n)));
  ScriptedWrite write{.outcomes = {WriteOutcome::kSent, WriteOutcome::kFailed},
                      .error_number = EINVAL};
  const auto flushed = queue.flush(t0, std::ref(write));
  EXPECT_EQ(flushed.retried, 2u);
  EXPECT_EQ(flushed.failed, 1u);
  EXPECT_EQ(write.written, (std::vector<std::uint8_t>{0, 1, 2}));
  EXPECT_TRUE(queue.empty());
}

TEST(RetryQueueTest, ALinkFaultThatClearsTheQueueEndsTheFlush) {
  RetryQueue queue(8);
  for (std::uint8_t n = 0; n < 3; ++n) ASSERT_TRUE(queue.push(numbered(n)));
  int calls = 0;
  std::size_t cleared = 0;
  const auto flushed = queue.flush(t0, [&](const can_frame&, int& error) {
    ++calls;
    cleared = queue.clear();  // what the bus does on ENETDOWN or ENODEV
    error = ENETDOWN;
    return WriteOutcome::kFailed;
  });
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(cleared, 3u);
  EXPECT_EQ(flushed.retried, 0u);
  EXPECT_EQ(flushed.failed, 0u);  // counted by whoever cleared them
  EXPECT_TRUE(queue.empty());
}

TEST(RetryQueueTest, ClearCountsAndStartsOver) {
  RetryQueue queue(8);
  ASSERT_TRUE(queue.push(numbered(0)));
  ASSERT_TRUE(queue.push(numbered(1)));
  queue.refused(ENOBUFS, t0);
  queue.refused(EAGAIN, t0);
  EXPECT_EQ(queue.clear(), 2u);
  EXPECT_TRUE(queue.empty());
  EXPECT_EQ(queue.clear(), 0u);
  ASSERT_TRUE(queue.push(numbered(2)));
  EXPECT_FALSE(queue.waits_for_pollout());
  queue.refused(ENOBUFS, t0);
  EXPECT_EQ(queue.retry_at(), t0 + 2ms);  // backoff from the start again
}

}  // namespace
}  // namespace teejet::can
