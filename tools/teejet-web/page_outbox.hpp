#pragma once

// One open page's outbox. Its messages are written by a thread of its own, so that a page that
// stops reading (a stalled browser, a dead link) blocks only that thread and never the tick that
// feeds every page. No CivetWeb here: the server hands in the function that writes a frame.

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <nlohmann/json.hpp>
#include <stop_token>
#include <string>
#include <string_view>
#include <thread>

namespace teejet::web {

// A page with this many messages not yet written (10 s of ticks) is not reading: it is dropped.
inline constexpr std::size_t kMaxQueuedMessages = 250;

class PageOutbox {
 public:
  enum class Frame { kText, kClose };
  // Writes one WebSocket frame to the page. It may block as long as the page does not read, and
  // must fail at once when the connection is closed (CivetWeb's write does both).
  using Write = std::function<void(Frame frame, std::string_view payload)>;

  explicit PageOutbox(Write write);
  // Joins the writer: the server lets an outbox go in CivetWeb's close callback, once the
  // connection is done, so a write still under way fails at once.
  ~PageOutbox();
  PageOutbox(const PageOutbox&) = delete;
  PageOutbox& operator=(const PageOutbox&) = delete;

  // Queues `message`; true when that dropped the page (the caller says so once). A page whose
  // outbox reaches kMaxQueuedMessages is dropped: its outbox is emptied, it is fed no more and is
  // sent one close, 1008 policy violation (the browser reconnects and starts from a snapshot).
  bool post(const nlohmann::json& message);

 private:
  void run(const std::stop_token& stop);

  const Write write_;
  std::mutex mutex_;
  std::condition_variable_any wake_;
  std::deque<std::string> outbox_;
  bool dropped_ = false;
  // Last: started once the members it uses exist, stopped and joined before they go.
  std::jthread writer_{[this](const std::stop_token& stop) { run(stop); }};
};

}  // namespace teejet::web
