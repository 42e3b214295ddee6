#pragma once

// One open page's outbox: the messages waiting for their WebSocket write, bounded, so that a page
// that stops reading (a stalled browser, a dead link) costs a bounded amount of memory and is
// dropped, while the tick that feeds every page never waits for it. No network and no threads:
// the server's one I/O thread posts, takes the next frame to write and says when a write is done,
// one write at a time (as a WebSocket stream allows).

#include <cstddef>
#include <deque>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

namespace teejet::web {

// A page with this many messages waiting behind the one being written (10 s of ticks) is not
// reading: it is dropped.
inline constexpr std::size_t kMaxQueuedMessages = 250;

// The close of a dropped page: 1008, policy violation.
inline constexpr unsigned kPolicyViolation = 1008;

class PageOutbox {
 public:
  enum class Frame { kText, kClose };
  struct Write {
    Frame frame;
    std::string text;  // empty for the close
    bool operator==(const Write&) const = default;
  };

  // Queues `message`; true when that dropped the page (the caller says so once). A page whose
  // outbox already holds kMaxQueuedMessages is dropped: its outbox is emptied, it is fed no more
  // and its next write is one close, 1008 (the browser reconnects and starts from a snapshot).
  bool post(const nlohmann::json& message);

  // The next frame to write, when none is being written and one waits; it is then being written
  // until write_done(). After the close, nothing more.
  std::optional<Write> start_write();
  void write_done();

  bool dropped() const { return dropped_; }

 private:
  std::deque<std::string> waiting_;
  bool writing_ = false;
  bool dropped_ = false;
  bool closed_ = false;  // the close was handed out
};

}  // namespace teejet::web
