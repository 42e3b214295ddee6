#include "page_outbox.hpp"

#include <utility>

namespace teejet::web {

PageOutbox::PageOutbox(Write write) : write_(std::move(write)) {}

PageOutbox::~PageOutbox() = default;

bool PageOutbox::post(const nlohmann::json& message) {
  std::lock_guard lock(mutex_);
  if (dropped_) return false;
  if (outbox_.size() >= kMaxQueuedMessages) {
    dropped_ = true;
    outbox_.clear();
    wake_.notify_one();
    return true;
  }
  outbox_.push_back(message.dump());
  wake_.notify_one();
  return false;
}

void PageOutbox::run(const std::stop_token& stop) {
  std::unique_lock lock(mutex_);
  while (wake_.wait(lock, stop, [this] { return dropped_ || !outbox_.empty(); })) {
    if (dropped_) {
      lock.unlock();
      static constexpr char kPolicyViolation[] = {0x03, static_cast<char>(0xF0)};  // 1008
      write_(Frame::kClose, {kPolicyViolation, 2});
      return;
    }
    const std::string text = std::move(outbox_.front());
    outbox_.pop_front();
    lock.unlock();
    write_(Frame::kText, text);
    lock.lock();
  }
}

}  // namespace teejet::web
