// The "target" of each valve: where teejet-web's own running move is heading.

#include <gtest/gtest.h>

#include "command_samples.hpp"
#include "target_tracker.hpp"

namespace teejet::web {
namespace {

using testing::move;
using testing::status;

TEST(WebTargets, AMoveSetsTheTargetUntilItsFinalStatus) {
  TargetTracker tracker;
  tracker.on_sent(move(1, 7, 74.6f));
  EXPECT_EQ(tracker.targets(), (Targets{{1, 74.6}}));
  tracker.on_status(status(1, 7, COMMAND_ACCEPTED));
  EXPECT_EQ(tracker.targets(), (Targets{{1, 74.6}}));
  tracker.on_status(status(1, 7, COMMAND_COMPLETED));
  EXPECT_TRUE(tracker.targets().empty());
}

TEST(WebTargets, ALateStatusOfAnOlderMoveLeavesTheNewTargetAndAStopClearsIt) {
  TargetTracker tracker;
  tracker.on_sent(move(1, 7, 10.0f));
  tracker.on_sent(move(1, 8, 20.0f));
  tracker.on_status(status(1, 7, COMMAND_SUPERSEDED));
  EXPECT_EQ(tracker.targets(), (Targets{{1, 20.0}}));
  ValveCommand stop;
  stop.serial(1);
  stop.command_id(9);
  stop.kind(COMMAND_STOP);
  tracker.on_sent(stop);
  EXPECT_TRUE(tracker.targets().empty());
}

}  // namespace
}  // namespace teejet::web
