// The "target" of each valve: where teejet-web's own running move is heading.

#include <gtest/gtest.h>

#include "command_samples.hpp"
#include "target_tracker.hpp"

namespace teejet::web {
namespace {

using testing::from;
using testing::kOrigin;
using testing::move_to;
using testing::status;
using testing::stop;

TEST(WebTargets, AMoveSetsTheTargetUntilItsFinalStatus) {
  TargetTracker tracker;
  tracker.on_sent(from(kOrigin, 7, move_to(1, 74.6f)));
  EXPECT_EQ(tracker.targets(), (Targets{{1, 74.6}}));
  tracker.on_status(status(1, 7, COMMAND_ACCEPTED));
  EXPECT_EQ(tracker.targets(), (Targets{{1, 74.6}}));
  tracker.on_status(status(1, 7, COMMAND_COMPLETED));
  EXPECT_TRUE(tracker.targets().empty());
}

TEST(WebTargets, ALateStatusOfAnOlderMoveLeavesTheNewTargetAndAStopClearsIt) {
  TargetTracker tracker;
  tracker.on_sent(from(kOrigin, 7, move_to(1, 10.0f)));
  tracker.on_sent(from(kOrigin, 8, move_to(1, 20.0f)));
  tracker.on_status(status(1, 7, COMMAND_SUPERSEDED));
  EXPECT_EQ(tracker.targets(), (Targets{{1, 20.0}}));
  tracker.on_sent(from(kOrigin, 9, stop(1)));
  EXPECT_TRUE(tracker.targets().empty());
}

}  // namespace
}  // namespace teejet::web
