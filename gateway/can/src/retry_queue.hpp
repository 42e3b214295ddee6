#pragma once

// The ENOBUFS retry queue: frames the kernel refused for now (device queue full, socket buffer
// full), kept in order and written again later, bounded so that nothing is buffered without
// limit. Pure bookkeeping: the caller passes the time and the write; unit-tested on the host
// (tests/can/retry_queue_tests.cpp).

#include <linux/can.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>

#include "teejet/core/time.hpp"

namespace teejet::can {

// How one write went, as far as the retry queue cares.
enum class WriteOutcome : std::uint8_t {
  kSent,
  kBusy,    // ENOBUFS or EAGAIN: no room now, the frame may go out later
  kFailed,  // anything else: this frame will not go out
};

class RetryQueue {
 public:
  static constexpr Duration kBackoffMin = std::chrono::milliseconds{2};
  static constexpr Duration kBackoffMax = std::chrono::milliseconds{64};

  explicit RetryQueue(std::size_t limit) : limit_(limit) {}

  bool empty() const { return frames_.empty(); }
  std::size_t size() const { return frames_.size(); }

  // Appends a refused frame behind the others; false, keeping nothing, when `limit` frames wait.
  bool push(const can_frame& frame);

  // The kernel refused with `error_number` at `now`; schedules the next attempt. After EAGAIN
  // (socket buffer full) on POLLOUT. After ENOBUFS (device queue full) on a timer that doubles
  // from kBackoffMin to kBackoffMax: the socket stays writable while the qdisc refuses, so
  // waiting for POLLOUT would spin.
  void refused(int error_number, SteadyTime now);
  // The next refusal starts the backoff from kBackoffMin again.
  void restart_backoff() { backoff_ = kBackoffMin; }

  bool waits_for_pollout() const { return !frames_.empty() && on_pollout_; }
  // Frames wait for the timer, and it has expired.
  bool due(SteadyTime now) const { return !frames_.empty() && !on_pollout_ && now >= retry_at_; }
  SteadyTime retry_at() const { return retry_at_; }

  // Drops every frame (the link is down or gone: stale valve commands must not go out seconds
  // later) and returns how many.
  std::size_t clear();

  struct Flushed {
    std::size_t retried = 0;  // written now
    std::size_t failed = 0;   // dropped: the kernel refused them for good
  };

  // Writes queued frames in order until the kernel refuses again. `write(frame, error_number)`
  // returns a WriteOutcome and sets error_number when not sent; it may clear() this queue (a
  // link fault drops every frame), which ends the flush.
  template <class Write>
  Flushed flush(SteadyTime now, Write&& write) {
    Flushed out;
    while (!frames_.empty()) {
      int error_number = 0;
      switch (write(frames_.front(), error_number)) {
        case WriteOutcome::kSent:
          frames_.pop_front();
          ++out.retried;
          break;
        case WriteOutcome::kBusy:
          refused(error_number, now);
          return out;
        case WriteOutcome::kFailed:
          if (!frames_.empty()) {  // not cleared by a link fault: drop this one frame
            frames_.pop_front();
            ++out.failed;
          }
          break;
      }
    }
    reset();
    return out;
  }

 private:
  void reset() {
    backoff_ = kBackoffMin;
    on_pollout_ = false;
  }

  const std::size_t limit_;
  std::deque<can_frame> frames_;
  bool on_pollout_ = false;  // the last refusal was EAGAIN: wait for POLLOUT, not the timer
  SteadyTime retry_at_{};
  Duration backoff_ = kBackoffMin;
};

}  // namespace teejet::can
