#pragma once

// The time between a recording's messages as the recorder lived it, without the steps of its
// wall clock. teejet-record now stamps log times on a step-free timeline; files recorded before
// carry the steps (a clock set back an hour made a 14 s file read as 3,600 s, and replay wait the
// hour; one set 10 years ahead, replay wait 10 years). Fed every message in file order, this
// gives each message's offset from the first with the steps taken out, for replay's pacing and
// --info's duration alike.

#include <cstdint>

namespace teejet::recording {

class ClockSteps {
 public:
  // Back by more than this: a step (less is the recorder's reordering of late samples, a gap of
  // nothing).
  static constexpr std::int64_t kLargestBackNs = 1'000'000'000;
  // Forward by more than this beyond what the publish times (the gateways' clocks) moved
  // meanwhile: a step of the recorder's clock alone.
  static constexpr std::int64_t kLargestAheadNs = 5'000'000'000;
  // Forward by more than this whatever the publish times did: a step of a clock the gateways
  // share with the recorder (a gateway publishes its status every second, so a teejet recording
  // is never quiet this long).
  static constexpr std::int64_t kLongestQuietNs = 600'000'000'000;

  // The offset of the next message (in file order) from the first, in nanoseconds.
  std::uint64_t next(std::uint64_t log_time, std::uint64_t publish_time) {
    ++messages_;
    if (messages_ == 1) {
      remember(log_time, publish_time);
      return 0;
    }
    const auto gap = static_cast<std::int64_t>(log_time - last_log_);
    const auto published = static_cast<std::int64_t>(publish_time - last_publish_);
    remember(log_time, publish_time);
    const bool step = gap < -kLargestBackNs || gap > kLongestQuietNs ||
                      (gap > kLargestAheadNs && gap - published > kLargestAheadNs);
    if (step) {
      ++steps_;
      if (largest_ == 0 || (gap < 0 ? -gap : gap) > (largest_ < 0 ? -largest_ : largest_)) {
        largest_ = gap;
        largest_at_ = messages_;
      }
      return offset_;
    }
    if (gap > 0) offset_ += static_cast<std::uint64_t>(gap);
    return offset_;
  }

  std::uint64_t steps() const { return steps_; }
  // The largest step (negative: back), and the message (counting from 1) that came after it.
  std::int64_t largest_step_ns() const { return largest_; }
  std::uint64_t largest_step_at() const { return largest_at_; }

 private:
  void remember(std::uint64_t log_time, std::uint64_t publish_time) {
    last_log_ = log_time;
    last_publish_ = publish_time;
  }

  std::uint64_t messages_ = 0;
  std::uint64_t last_log_ = 0;
  std::uint64_t last_publish_ = 0;
  std::uint64_t offset_ = 0;
  std::uint64_t steps_ = 0;
  std::int64_t largest_ = 0;
  std::uint64_t largest_at_ = 0;
};

}  // namespace teejet::recording
