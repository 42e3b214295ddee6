#pragma once

// The one time vocabulary of every layer. Two clocks, never mixed up by the type system:
// - Timestamp, the wall clock: when a frame was received, in samples other machines read. It
//   may jump (NTP, GPS, a person setting the date), so nothing is ever timed with it.
// - SteadyTime, the monotonic clock: deadlines, timeouts, periods, offline expiry.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>

namespace teejet {

using Duration = std::chrono::nanoseconds;
using Timestamp = std::chrono::time_point<std::chrono::system_clock, Duration>;
using SteadyTime = std::chrono::time_point<std::chrono::steady_clock, Duration>;

// Nanoseconds since the Unix epoch, as the IDL's *_ns fields carry them (0 before 1970).
std::uint64_t unix_nanoseconds(Timestamp time);
Timestamp from_unix_nanoseconds(std::uint64_t nanoseconds);

// A number of seconds as people configure it, as a Duration: NaN and negatives give 0, values
// beyond the range of Duration (about 292 years) give its maximum instead of overflowing.
Duration seconds(double value);

// Where time comes from. Injected so that tests step time deterministically, and can step the
// wall clock alone as an NTP correction would.
class Clock {
 public:
  virtual ~Clock() = default;
  virtual Timestamp wall() const = 0;
  virtual SteadyTime steady() const = 0;
};

// The system's real clocks (CLOCK_REALTIME and CLOCK_MONOTONIC).
std::shared_ptr<const Clock> system_clock();

// A clock that moves only when told to. Thread-safe.
class ManualClock final : public Clock {
 public:
  explicit ManualClock(Timestamp wall_start = Timestamp{}, SteadyTime steady_start = SteadyTime{});
  Timestamp wall() const override;
  SteadyTime steady() const override;
  // Time passes: both clocks move.
  void advance(Duration by);
  // Someone sets the date: only the wall clock moves (forward or back).
  void step_wall(Duration by);

 private:
  std::atomic<Duration::rep> wall_;
  std::atomic<Duration::rep> steady_;
};

}  // namespace teejet
