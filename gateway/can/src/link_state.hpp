#pragma once

// The link state machine of a SocketCAN interface: up, down (ENETDOWN: the socket is kept) and
// gone (ENODEV/ENXIO: the socket is closed and reopened with backoff), with the timers of each.
// Pure: the caller passes the time and makes the system calls (asking the interface's flags,
// reopening); every transition returns whether it changed the state, so the caller logs once per
// change. Unit-tested on the host (tests/can/link_state_tests.cpp).
//
//          ENETDOWN                  ENODEV/ENXIO
//   up ──────────────▶ down ──────────────────────▶ gone
//    ▲  frame, write,    │  flags every 100 ms        │  reopen after min, 2×min, … ≤ max
//    └──── IFF_UP ───────┘                            │
//    ▲                                                │
//    └───────────────── opened (up or down) ◀─────────┘
//
// A bus told to wait for its interface (SocketCanOptions::wait_for_interface) that finds none at
// open() starts gone: closed ──missing──▶ gone, and from there as above.

#include <chrono>
#include <cstdint>

#include "teejet/core/time.hpp"

namespace teejet::can {

class LinkState {
 public:
  enum class State : std::uint8_t { kClosed, kUp, kDown, kGone };

  // While the link is down, how often the interface flags are asked (SIOCGIFFLAGS) to notice
  // that it is up again when no frame arrives to say so.
  static constexpr Duration kCheckInterval = std::chrono::milliseconds{100};

  LinkState(Duration reopen_backoff_min, Duration reopen_backoff_max)
      : reopen_min_(reopen_backoff_min), reopen_max_(reopen_backoff_max) {}

  State state() const { return state_; }
  // Down or gone: what statistics() shows as BusState::kDown.
  bool faulty() const { return state_ == State::kDown || state_ == State::kGone; }

  // A socket was bound (open() or a reopen): up or down as the interface flags said.
  void opened(bool up, SteadyTime now);
  // open() found no interface and waits for one: closed → gone, first attempt after the minimum.
  void missing(SteadyTime now);
  // close(): nothing to watch any more.
  void closed() { state_ = State::kClosed; }

  // ENETDOWN: up → down; the flags are asked kCheckInterval from now.
  bool down(SteadyTime now);
  // A frame read, a write that went out, IFF_UP: down → up.
  bool up();
  // ENODEV/ENXIO: up or down → gone; the first reopen attempt after reopen_backoff_min.
  bool vanished(SteadyTime now);
  // A reopen attempt failed: the next one after twice the last backoff, at most the maximum.
  void reopen_failed(SteadyTime now);

  // Gone, and the next reopen attempt is due.
  bool reopen_due(SteadyTime now) const { return state_ == State::kGone && now >= reopen_at_; }
  // Down, and the interface flags are due to be asked; checked() schedules the next time.
  bool check_due(SteadyTime now) const { return state_ == State::kDown && now >= check_at_; }
  void checked(SteadyTime now) { check_at_ = now + kCheckInterval; }

  // The earlier of `deadline` and the timer of the current state: how long a receiver may sleep.
  SteadyTime next_wake(SteadyTime deadline) const;

  Duration reopen_backoff() const { return reopen_backoff_; }

 private:
  const Duration reopen_min_;
  const Duration reopen_max_;
  State state_ = State::kClosed;
  SteadyTime check_at_{};
  SteadyTime reopen_at_{};
  Duration reopen_backoff_{};
};

}  // namespace teejet::can
