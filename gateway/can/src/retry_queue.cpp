#include "retry_queue.hpp"

#include <algorithm>
#include <cerrno>

namespace teejet::can {

bool RetryQueue::push(const can_frame& frame) {
  if (frames_.size() >= limit_) return false;
  frames_.push_back(frame);
  return true;
}

void RetryQueue::refused(int error_number, SteadyTime now) {
  on_pollout_ = error_number == EAGAIN;
  retry_at_ = now + backoff_;
  backoff_ = std::min(backoff_ * 2, kBackoffMax);
}

std::size_t RetryQueue::clear() {
  const std::size_t count = frames_.size();
  frames_.clear();
  reset();
  return count;
}

}  // namespace teejet::can
