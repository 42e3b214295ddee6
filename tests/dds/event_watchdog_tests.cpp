// The event watchdog (dds/event_watchdog.hpp) says when a participant's Fast DDS event thread
// stops running timers, as the deadlock of docs/topics.md ("A participant that stops") leaves
// it. The test holds that thread in a listener of its own instead of waiting for the race.

#include <gtest/gtest.h>

#include <condition_variable>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <mutex>

#include "support/eventually.hpp"
#include "support/test_domain.hpp"
#include "teejet/dds/event_watchdog.hpp"
#include "teejet/dds/participant.hpp"

namespace teejet::dds {
namespace {

using namespace std::chrono_literals;
using namespace eprosima::fastdds::dds;
using teejet::testing::eventually;
using teejet::testing::test_domain;

// Holds the event thread in its first missed-deadline callback until released.
class HoldingListener final : public DataWriterListener {
 public:
  void on_offered_deadline_missed(DataWriter*, const OfferedDeadlineMissedStatus&) override {
    std::unique_lock lock(mutex_);
    holding_ = true;
    changed_.notify_all();
    changed_.wait(lock, [this] { return released_; });
  }
  bool holding() {
    std::lock_guard lock(mutex_);
    return holding_;
  }
  void release() {
    std::lock_guard lock(mutex_);
    released_ = true;
    changed_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  bool holding_ = false;
  bool released_ = false;
};

struct Stall {
  std::mutex mutex;
  int reports = 0;
  Duration silent_for{};
};

// Beats every 100 ms; a stall after 2 s without one is counted in `stall`.
Result<std::unique_ptr<EventWatchdog>> watch(Participant& participant,
                                             std::shared_ptr<Stall> stall) {
  return EventWatchdog::create(
      participant,
      {.period = 100ms, .stalled_after = 2s, .on_stalled = [stall](Duration silent_for) {
         std::lock_guard lock(stall->mutex);
         ++stall->reports;
         stall->silent_for = silent_for;
       }});
}

TEST(EventWatchdog, BeatsWhileTheEventThreadRunsAndReportsOnceWhenItStops) {
  // Outlives the participant: the event thread calls it again after release, until the
  // writer is gone.
  HoldingListener holding;
  auto participant = Participant::create({.domain = test_domain(), .name = "watched"});
  ASSERT_TRUE(participant) << participant.error().reason;
  auto stall = std::make_shared<Stall>();
  auto watchdog = watch(**participant, stall);
  ASSERT_TRUE(watchdog) << watchdog.error().reason;
  ASSERT_TRUE(eventually([&] { return (*watchdog)->beats() >= 10; }, 10s))
      << (*watchdog)->beats() << " beats";
  {
    std::lock_guard lock(stall->mutex);
    EXPECT_EQ(stall->reports, 0) << "a stall reported while the event thread ran";
  }

  // A writer whose first missed deadline keeps the event thread, as the deadlock does.
  auto topic = (*participant)->topic<ValvePositionPubSubType>("test/event_watchdog/holder");
  ASSERT_TRUE(topic) << topic.error().reason;
  DataWriterQos qos = DATAWRITER_QOS_DEFAULT;
  qos.reliability().kind = BEST_EFFORT_RELIABILITY_QOS;
  qos.deadline().period = to_dds_duration(50ms);
  auto holder = (*participant)->writer(*topic, qos, &holding);
  ASSERT_TRUE(holder) << holder.error().reason;
  ValvePosition sample;
  ASSERT_TRUE((*holder)->write(&sample));
  ASSERT_TRUE(eventually([&] { return holding.holding(); }, 10s));
  const auto beats_when_held = (*watchdog)->beats();

  const bool reported = eventually(
      [&] {
        std::lock_guard lock(stall->mutex);
        return stall->reports > 0;
      },
      30s);
  holding.release();  // before anything below waits for the event thread
  ASSERT_TRUE(reported) << "no stall reported";
  EXPECT_LE((*watchdog)->beats(), beats_when_held + 1);
  std::lock_guard lock(stall->mutex);
  EXPECT_EQ(stall->reports, 1);
  EXPECT_GE(stall->silent_for, 2s);
}

// A program deletes its participant with the watchdog still watching (Gateway::stop): the
// writer goes with the participant, and a deletion that never ends would be reported.
TEST(EventWatchdog, WatchesOnWhileItsParticipantIsDeleted) {
  auto participant = Participant::create({.domain = test_domain(), .name = "deleted"});
  ASSERT_TRUE(participant) << participant.error().reason;
  auto stall = std::make_shared<Stall>();
  auto watchdog = watch(**participant, stall);
  ASSERT_TRUE(watchdog) << watchdog.error().reason;
  ASSERT_TRUE(eventually([&] { return (*watchdog)->beats() >= 3; }, 10s));

  (*watchdog)->outlive_participant();
  participant->reset();
  const auto beats_after = (*watchdog)->beats();
  // No beat without the writer: to the watchdog that is a deletion that did not end.
  EXPECT_TRUE(eventually(
      [&] {
        std::lock_guard lock(stall->mutex);
        return stall->reports > 0;
      },
      30s))
      << "the watchdog stopped watching when its writer went with the participant";
  EXPECT_EQ((*watchdog)->beats(), beats_after);
  watchdog->reset();
  std::lock_guard lock(stall->mutex);
  EXPECT_EQ(stall->reports, 1);
}

}  // namespace
}  // namespace teejet::dds
