// One page's outbox: its messages in order, one write at a time, and the drop of a page that
// stops reading, after which it gets one close and nothing else.

#include <gtest/gtest.h>

#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "page_outbox.hpp"

namespace teejet::web {

// Found by gtest next to PageOutbox::Write, so that a failure shows the frames.
void PrintTo(const PageOutbox::Write& write, std::ostream* out);
void PrintTo(const PageOutbox::Write& write, std::ostream* out) {
  *out << (write.frame == PageOutbox::Frame::kText ? "text " + write.text : std::string("close"));
}

namespace {

using Write = PageOutbox::Write;
using Frame = PageOutbox::Frame;

Write text(int n) { return {Frame::kText, std::to_string(n)}; }
const Write kClose{Frame::kClose, {}};

// Writes everything the outbox hands out, each write completing at once: what a page that reads
// receives.
std::vector<Write> drain(PageOutbox& outbox) {
  std::vector<Write> written;
  while (const auto next = outbox.start_write()) {
    written.push_back(*next);
    outbox.write_done();
  }
  return written;
}

TEST(WebPageOutbox, MessagesAreWrittenInTheOrderTheyWerePosted) {
  PageOutbox outbox;
  const int count = static_cast<int>(kMaxQueuedMessages);
  for (int n = 1; n <= count; ++n) EXPECT_FALSE(outbox.post(n));
  std::vector<Write> expected;
  for (int n = 1; n <= count; ++n) expected.push_back(text(n));
  EXPECT_EQ(drain(outbox), expected);
  EXPECT_FALSE(outbox.dropped());
}

TEST(WebPageOutbox, OneWriteAtATime) {
  PageOutbox outbox;
  EXPECT_FALSE(outbox.post(1));
  EXPECT_FALSE(outbox.post(2));
  EXPECT_EQ(outbox.start_write(), text(1));
  EXPECT_EQ(outbox.start_write(), std::nullopt);  // 1 is still being written
  outbox.write_done();
  EXPECT_EQ(outbox.start_write(), text(2));
  outbox.write_done();
  EXPECT_EQ(outbox.start_write(), std::nullopt);  // nothing waits
}

TEST(WebPageOutbox, APageThatDoesNotReadIsDroppedAtTheLimitAndClosedOnce) {
  PageOutbox outbox;
  EXPECT_FALSE(outbox.post(0));
  ASSERT_EQ(outbox.start_write(), text(0));  // and its write never completes: the page is stalled
  const int count = static_cast<int>(kMaxQueuedMessages);
  for (int n = 1; n <= count; ++n) ASSERT_FALSE(outbox.post(n)) << "message " << n;
  // 250 messages wait (1 to 250; 0 is being written): the next one drops the page, once.
  EXPECT_TRUE(outbox.post(251));
  EXPECT_TRUE(outbox.dropped());
  EXPECT_FALSE(outbox.post(252));
  EXPECT_EQ(outbox.start_write(), std::nullopt);  // 0 is still being written
  outbox.write_done();
  // What waited is gone: the page gets its close and nothing after it.
  EXPECT_EQ(drain(outbox), std::vector<Write>{kClose});
  EXPECT_FALSE(outbox.post(253));
  EXPECT_EQ(outbox.start_write(), std::nullopt);
}

TEST(WebPageOutbox, APageThatReadsGetsEveryMessageWhileAnotherIsDropped) {
  PageOutbox stalled;
  PageOutbox reading;
  EXPECT_FALSE(stalled.post(0));
  ASSERT_EQ(stalled.start_write(), text(0));
  const int count = static_cast<int>(kMaxQueuedMessages);
  std::vector<Write> expected;
  std::vector<Write> written;
  for (int n = 1; n <= 2 * count; ++n) {
    stalled.post(n);
    EXPECT_FALSE(reading.post(n));
    expected.push_back(text(n));
    for (const Write& write : drain(reading)) written.push_back(write);
  }
  EXPECT_TRUE(stalled.dropped());
  EXPECT_EQ(written, expected);
  EXPECT_FALSE(reading.dropped());
}

}  // namespace
}  // namespace teejet::web
