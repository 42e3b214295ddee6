#include "page_outbox.hpp"

#include <utility>

namespace teejet::web {

bool PageOutbox::post(const nlohmann::json& message) {
  if (dropped_) return false;
  if (waiting_.size() >= kMaxQueuedMessages) {
    dropped_ = true;
    waiting_.clear();
    return true;
  }
  waiting_.push_back(message.dump());
  return false;
}

std::optional<PageOutbox::Write> PageOutbox::start_write() {
  if (writing_ || closed_) return std::nullopt;
  if (dropped_) {
    writing_ = closed_ = true;
    return Write{Frame::kClose, {}};
  }
  if (waiting_.empty()) return std::nullopt;
  writing_ = true;
  Write next{Frame::kText, std::move(waiting_.front())};
  waiting_.pop_front();
  return next;
}

void PageOutbox::write_done() { writing_ = false; }

}  // namespace teejet::web
