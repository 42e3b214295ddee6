#pragma once

#include <atomic>
#include <chrono>
#include <memory>

namespace teejet::can {

// Wall-clock time in nanoseconds since the Unix epoch: what SocketCAN stamps frames with and
// what DDS consumers compare across machines.
using Timestamp = std::chrono::nanoseconds;

// Where time comes from. Injected so that timing (receive stamps, valve motion, resend
// periods) can be stepped deterministically in tests.
class Clock {
 public:
  virtual ~Clock() = default;
  virtual Timestamp now() const = 0;
};

// The system's real-time clock.
std::shared_ptr<const Clock> system_clock();

// A clock that moves only when told to.
class ManualClock final : public Clock {
 public:
  explicit ManualClock(Timestamp start = Timestamp{0}) : now_(start.count()) {}
  Timestamp now() const override { return Timestamp{now_.load()}; }
  void advance(Timestamp by) { now_ += by.count(); }
  void set(Timestamp to) { now_ = to.count(); }

 private:
  std::atomic<Timestamp::rep> now_;
};

}  // namespace teejet::can
