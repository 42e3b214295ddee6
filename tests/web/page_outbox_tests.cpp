// One page's outbox: its messages in order, and the drop of a page that stops reading, which
// costs no other page anything.

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "page_outbox.hpp"
#include "support/eventually.hpp"

namespace teejet::web {
namespace {

using namespace std::chrono_literals;
using teejet::testing::eventually;

constexpr auto kDeadline = 10s;

struct Written {
  PageOutbox::Frame frame;
  std::string payload;
  bool operator==(const Written&) const = default;
};

void PrintTo(const Written& written, std::ostream* out) {
  *out << (written.frame == PageOutbox::Frame::kText ? "text " : "close ");
  for (const char c : written.payload) *out << std::hex << +static_cast<unsigned char>(c) << ' ';
}

// The messages `first` to `last` as posted below: the numbers themselves, as JSON text.
std::vector<Written> texts(int first, int last) {
  std::vector<Written> written;
  for (int n = first; n <= last; ++n)
    written.push_back({PageOutbox::Frame::kText, std::to_string(n)});
  return written;
}

// The close of a dropped page: status code 1008 (policy violation), big-endian.
const Written kPolicyViolationClose{PageOutbox::Frame::kClose, std::string{'\x03', '\xF0'}};

// The page end of a WebSocket, as the outbox's write function reaches it. A held page does not
// read: a write blocks until the test lets it go, or closes the page, after which that write and
// every later one fail at once, as CivetWeb's do once the connection is closed.
class FakePage {
 public:
  explicit FakePage(bool held = false) : held_(held) {}

  PageOutbox::Write write_function() {
    return [this](PageOutbox::Frame frame, std::string_view payload) { write(frame, payload); };
  }

  void let_go() {
    std::lock_guard lock(mutex_);
    held_ = false;
    changed_.notify_all();
  }

  void close() {
    std::lock_guard lock(mutex_);
    closed_ = true;
    changed_.notify_all();
  }

  std::size_t writes_blocked() const {
    std::lock_guard lock(mutex_);
    return writes_blocked_;
  }

  std::vector<Written> written() const {
    std::lock_guard lock(mutex_);
    return written_;
  }

 private:
  void write(PageOutbox::Frame frame, std::string_view payload) {
    std::unique_lock lock(mutex_);
    ++writes_blocked_;
    changed_.wait(lock, [this] { return !held_ || closed_; });
    --writes_blocked_;
    if (closed_) return;
    written_.push_back({frame, std::string(payload)});
  }

  mutable std::mutex mutex_;
  std::condition_variable changed_;
  bool held_;
  bool closed_ = false;
  std::size_t writes_blocked_ = 0;
  std::vector<Written> written_;
};

// A page that reads and one that does not, each with its outbox.
class WebPageOutbox : public ::testing::Test {
 protected:
  // As CivetWeb closes a connection before it lets the page's outbox go; a test that failed
  // midway then ends instead of waiting for a held write.
  void TearDown() override {
    stalled.close();
    reading.close();
  }

  // Posts message 0, which the stalled page's writer takes and blocks on, then `count` more.
  void fill_stalled(int count) {
    EXPECT_FALSE(stalled_outbox->post(0));
    ASSERT_TRUE(eventually([this] { return stalled.writes_blocked() == 1; }, kDeadline));
    for (int n = 1; n <= count; ++n) ASSERT_FALSE(stalled_outbox->post(n)) << "message " << n;
  }

  FakePage reading;
  FakePage stalled{true};
  PageOutbox reading_outbox{reading.write_function()};
  std::optional<PageOutbox> stalled_outbox{std::in_place, stalled.write_function()};
};

TEST_F(WebPageOutbox, MessagesAreWrittenInTheOrderTheyWerePosted) {
  // As many as may wait at once: none of them can drop the page, however slow its writer.
  const int count = static_cast<int>(kMaxQueuedMessages);
  for (int n = 1; n <= count; ++n) EXPECT_FALSE(reading_outbox.post(n));
  EXPECT_TRUE(
      eventually([&] { return reading.written().size() == kMaxQueuedMessages; }, kDeadline));
  EXPECT_EQ(reading.written(), texts(1, count));
}

TEST_F(WebPageOutbox, APageThatDoesNotReadIsDroppedAtTheLimitAndClosedOnce) {
  ASSERT_NO_FATAL_FAILURE(fill_stalled(static_cast<int>(kMaxQueuedMessages)));
  // 250 messages wait (1 to 250; the writer holds 0): the next one drops the page, once.
  EXPECT_TRUE(stalled_outbox->post(251));
  EXPECT_FALSE(stalled_outbox->post(252));
  stalled.let_go();
  EXPECT_TRUE(eventually([this] { return stalled.written().size() == 2; }, kDeadline));
  EXPECT_FALSE(stalled_outbox->post(253));
  stalled_outbox.reset();  // joins the writer: whatever it was ever to write is written
  EXPECT_EQ(stalled.written(),
            (std::vector<Written>{{PageOutbox::Frame::kText, "0"}, kPolicyViolationClose}));
}

TEST_F(WebPageOutbox, APageThatReadsGetsEveryMessageWhileAnotherIsDropped) {
  ASSERT_NO_FATAL_FAILURE(fill_stalled(static_cast<int>(kMaxQueuedMessages)));
  EXPECT_TRUE(stalled_outbox->post(251));
  const int count = static_cast<int>(kMaxQueuedMessages);
  for (int n = 1; n <= count; ++n) EXPECT_FALSE(reading_outbox.post(n));
  EXPECT_TRUE(
      eventually([&] { return reading.written().size() == kMaxQueuedMessages; }, kDeadline));
  EXPECT_EQ(reading.written(), texts(1, count));
  // Meanwhile the stalled page's writer still waits on message 0, and wrote nothing.
  EXPECT_EQ(stalled.writes_blocked(), 1u);
  EXPECT_TRUE(stalled.written().empty());
}

TEST_F(WebPageOutbox, DestroyingAnOutboxWhoseWriteBlocksReturnsOnceTheWriteFails) {
  ASSERT_NO_FATAL_FAILURE(fill_stalled(5));
  std::atomic<bool> destroyed{false};
  std::jthread closing([&] {
    stalled_outbox.reset();
    destroyed = true;
  });
  EXPECT_FALSE(destroyed);  // not while message 0's write still blocks
  stalled.close();
  EXPECT_TRUE(eventually([&] { return destroyed.load(); }, kDeadline));
  // Message 0's write failed, and so did those of 1 to 5, at once.
  EXPECT_TRUE(stalled.written().empty());
}

}  // namespace
}  // namespace teejet::web
