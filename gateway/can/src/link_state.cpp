#include "link_state.hpp"

#include <algorithm>

namespace teejet::can {

void LinkState::opened(bool up, SteadyTime now) {
  state_ = up ? State::kUp : State::kDown;
  check_at_ = now + kCheckInterval;
}

void LinkState::missing(SteadyTime now) {
  state_ = State::kGone;
  reopen_backoff_ = reopen_min_;
  reopen_at_ = now + reopen_backoff_;
}

bool LinkState::down(SteadyTime now) {
  if (state_ != State::kUp) return false;
  state_ = State::kDown;
  check_at_ = now + kCheckInterval;
  return true;
}

bool LinkState::up() {
  if (state_ != State::kDown) return false;
  state_ = State::kUp;
  return true;
}

bool LinkState::vanished(SteadyTime now) {
  if (state_ == State::kGone || state_ == State::kClosed) return false;
  state_ = State::kGone;
  reopen_backoff_ = reopen_min_;
  reopen_at_ = now + reopen_backoff_;
  return true;
}

void LinkState::reopen_failed(SteadyTime now) {
  reopen_backoff_ = std::min(reopen_backoff_ * 2, reopen_max_);
  reopen_at_ = now + reopen_backoff_;
}

SteadyTime LinkState::next_wake(SteadyTime deadline) const {
  switch (state_) {
    case State::kGone:
      return std::min(deadline, reopen_at_);
    case State::kDown:
      return std::min(deadline, check_at_);
    case State::kClosed:
    case State::kUp:
      break;
  }
  return deadline;
}

}  // namespace teejet::can
