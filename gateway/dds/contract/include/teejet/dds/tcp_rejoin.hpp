#pragma once

// When a client over TCP replaces its participant. Fast DDS 2.9.1's TCP transport may leave a
// participant that starts beside another one's start, connection or departure without meeting
// anyone, for good, while a new participant does get through (docs/remote-benches.md). A
// participant that has met no gateway `first` after it joined is replaced, its successor after
// twice as long, and so on up to `longest`; never once the participant met a gateway, when it
// does not use TCP (UDP discovery never stalled so, and a new participant would only add load),
// or once the client keeps it (something else holds it). valvectl and teejet-record follow it.

#include <algorithm>
#include <chrono>

#include "teejet/dds/participant.hpp"

namespace teejet::dds {

class TcpRejoin {
 public:
  using Clock = std::chrono::steady_clock;

  // Twice the longest a start beside a starting gateway took to meet it (1.1 s of 40,
  // remote_bench_test.py tcp-first-starts).
  static constexpr Clock::duration kFirst = std::chrono::seconds(2);

  explicit TcpRejoin(Clock::duration first = kFirst,
                     Clock::duration longest = Clock::duration::max())
      : interval_(first), longest_(longest) {}

  // A participant was made at `now`: the first, or a replacement (which gets twice as long).
  void joined(Clock::time_point now) {
    if (joins_++ > 0) interval_ = interval_ > longest_ / 2 ? longest_ : 2 * interval_;
    joined_at_ = now;
  }

  // When to look next; time_point::max() once the participant stays.
  Clock::time_point due() const {
    return kept_ ? Clock::time_point::max() : joined_at_ + interval_;
  }

  // Whether the participant is to be replaced now (the caller makes the new one and calls
  // joined()): due, over TCP, and no gateway met. Once it met one, or does not use TCP, it stays.
  bool replace(const Participant& participant, Clock::time_point now) {
    if (now < due()) return false;
    if (!participant.uses_tcp() || !participant.participants_with_role(kGatewayRole).empty()) {
      kept_ = true;
      return false;
    }
    return true;
  }

  void keep() { kept_ = true; }

  // How long the participant being replaced had: for the message that says so.
  Clock::duration waited() const { return interval_; }

 private:
  Clock::duration interval_;
  Clock::duration longest_;
  Clock::time_point joined_at_{};
  int joins_ = 0;
  bool kept_ = false;
};

}  // namespace teejet::dds
