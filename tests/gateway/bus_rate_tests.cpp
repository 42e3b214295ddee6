#include <gtest/gtest.h>

#include <array>

#include "teejet/gateway/bus_rate.hpp"

namespace teejet::gateway {
namespace {

using namespace std::chrono_literals;

constexpr unsigned kDefaultAbove = 3000;  // gateway.receive_coalesce_above_fps's default
const SteadyTime kStart{};

// The reader's batches of a bus that carries `per_tick` frames each 100 ms poll tick: the
// replies come one after another at wire speed, taken 64 at a time a millisecond apart, the
// tick a little early or late each time (the poll thread's and the reader's wake-ups).
struct Bursts {
  int per_tick;
  int ticks_busy = 0;  // steps judged busy while the bursts came
};

Bursts feed_bursts(BusRate& rate, int per_tick, std::size_t ticks, SteadyTime& now) {
  static constexpr std::array<Duration, 10> kJitter = {0us,    1500us,  -1500us, 500us,   -500us,
                                                       2000us, -2000us, 1000us,  -1000us, 200us};
  Bursts seen{per_tick};
  const SteadyTime first = now;
  for (std::size_t tick = 1; tick <= ticks; ++tick) {
    SteadyTime at = first + static_cast<int>(tick) * 100ms + kJitter[tick % kJitter.size()];
    for (int left = per_tick; left > 0; left -= 64) {
      rate.count(static_cast<std::size_t>(std::min(left, 64)), at);
      now = at;
      at += 1ms;
    }
    if (rate.busy()) ++seen.ticks_busy;
  }
  return seen;
}

// A full 500 kbit/s bus as the coalescing reader takes it: about 16 frames each 4 ms window.
void feed_even(BusRate& rate, int frames_per_second, Duration how_long, SteadyTime& now) {
  constexpr Duration kWindow = 4ms;
  const int per_window = frames_per_second * 4 / 1000;
  for (const SteadyTime until = now + how_long; now < until;) {
    now += kWindow;
    rate.count(static_cast<std::size_t>(per_window), now);
  }
}

TEST(BusRate, ABurstyBusBelowTheThresholdIsNeverBusy) {
  // 2,600 frames a second on average (32 valves at the full poll rate): a tenth of a second that
  // caught two ticks' bursts read 4,600 before, and held frames up for the window.
  BusRate rate(kDefaultAbove, kStart);
  SteadyTime now = kStart;
  EXPECT_EQ(feed_bursts(rate, 260, 600, now).ticks_busy, 0);
}

TEST(BusRate, AFullBusIsBusyAfterASecondAndStaysBusy) {
  BusRate rate(kDefaultAbove, kStart);
  SteadyTime now = kStart;
  feed_even(rate, 3900, 900ms, now);
  EXPECT_FALSE(rate.busy()) << "judged before a whole second was counted";
  feed_even(rate, 3900, 200ms, now);
  EXPECT_TRUE(rate.busy());
  for (int step = 0; step < 600; ++step) {
    feed_even(rate, 3900, 100ms, now);
    ASSERT_TRUE(rate.busy()) << "at step " << step;
  }
}

TEST(BusRate, ABusThatQuietensIsNoLongerBusyAfterATenth) {
  BusRate rate(kDefaultAbove, kStart);
  SteadyTime now = kStart;
  feed_even(rate, 3900, 5s, now);
  ASSERT_TRUE(rate.busy());
  feed_even(rate, 1000, 104ms, now);
  EXPECT_FALSE(rate.busy());
}

TEST(BusRate, AFullBusAfterAQuietSpellWaitsForItsSecond) {
  BusRate rate(kDefaultAbove, kStart);
  SteadyTime now = kStart;
  feed_even(rate, 3900, 5s, now);
  now += 10s;  // nothing on the bus
  rate.count(1, now);
  EXPECT_FALSE(rate.busy());
  feed_even(rate, 3900, 500ms, now);
  EXPECT_FALSE(rate.busy()) << "the quiet spell is within the last second's count";
  feed_even(rate, 3900, 1100ms, now);
  EXPECT_TRUE(rate.busy());
}

TEST(BusRate, ZeroMeansBusyAtAnyRateFromTheStart) {
  BusRate rate(0, kStart);
  EXPECT_TRUE(rate.busy());
  SteadyTime now = kStart;
  feed_even(rate, 10, 2s, now);
  EXPECT_TRUE(rate.busy());
}

}  // namespace
}  // namespace teejet::gateway
