// Deleting a writer while its readers have not acknowledged its samples returns (Fast DDS
// 2.9.1 could hang there forever: participant.cpp, empty_history). The deletions run in a peer
// process (writer_teardown.cpp) that this test kills if it is not done by the deadline.

#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "support/eventually.hpp"
#include "support/subprocess.hpp"
#include "support/test_domain.hpp"

namespace {

using namespace std::chrono_literals;
using teejet::testing::scaled;
using teejet::testing::Subprocess;
using teejet::testing::test_domain;

// Each round takes well under a second on an idle machine; the rest is room for a loaded one.
constexpr int kRounds = 20;
constexpr auto kDeadline = 120s;

TEST(WriterTeardown, AWriterWithUnacknowledgedSamplesIsDeletedEveryTime) {
  Subprocess peer({WRITER_TEARDOWN_PATH, std::to_string(test_domain()), std::to_string(kRounds)});
  const auto finished = peer.wait(scaled(kDeadline));
  EXPECT_EQ(finished.exit_code, 0) << "stdout: " << finished.out << "\nstderr: " << finished.err;
  EXPECT_NE(finished.out.find("done"), std::string::npos)
      << "the deletions did not all return within " << scaled(kDeadline).count()
      << " s; the last round done: " << finished.out;
}

}  // namespace
