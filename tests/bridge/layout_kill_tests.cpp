// The layout file under kills: layout_churn (a bridge saving every change through the gateway's
// own store) is killed at random moments while it applies layout changes as fast as it can. After
// every kill the file must load, and hold the layout of the last change whose status went out or
// of the one after it (saved, not yet answered): never a damaged file, never an answered change
// lost.

#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <random>
#include <sstream>
#include <thread>

#include "layout_churn.hpp"
#include "support/scratch_dir.hpp"
#include "support/subprocess.hpp"
#include "teejet/layout/layout_file.hpp"

namespace teejet::testing {
namespace {

using namespace std::chrono_literals;

constexpr int kKills = 200;

// The layouts after 0, 1, 2, ... changes of the churn, computed without the bridge.
class Expected {
 public:
  const layout::Layout& after(std::size_t changes) {
    while (layouts_.size() <= changes) {
      layout::Layout next = layouts_.back();
      const auto change = churn::change(layouts_.size() - 1);
      EXPECT_TRUE(next.assign(change.location, change.serial, /*move=*/true));
      layouts_.push_back(std::move(next));
    }
    return layouts_[changes];
  }

 private:
  std::vector<layout::Layout> layouts_{churn::start()};
};

// How many "answered N" lines, in order from 0; -1 when one is out of order or a change was
// refused.
long answered(const std::string& out) {
  std::istringstream lines(out);
  long count = 0;
  for (std::string line; std::getline(lines, line);) {
    if (lines.eof()) break;  // a line the kill cut short was never whole
    if (line.starts_with("refused")) return -1;
    if (!line.starts_with("answered ")) continue;
    if (std::stol(line.substr(9)) != count) return -1;
    ++count;
  }
  return count;
}

std::size_t leftovers(const std::filesystem::path& dir) {
  std::size_t count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    count += entry.path().filename() != "layout.yaml";
  }
  return count;
}

TEST(LayoutKill, AKillAtAnyMomentLeavesTheLastAnsweredLayoutOrTheNextWhole) {
  ScratchDir dir;
  const std::string file = dir / "layout.yaml";
  Expected expected;
  std::mt19937 random(20261127);
  std::uniform_int_distribution<int> pause_us(0, 20'000);
  int found_answered = 0;    // the file held the last answered change
  int found_unanswered = 0;  // it held the change after it: saved when the kill came
  std::size_t changes = 0;
  std::size_t unfinished = 0;
  for (int kill = 0; kill < kKills; ++kill) {
    ASSERT_TRUE(layout::save_layout_file(file, churn::start()));
    Subprocess churning({LAYOUT_CHURN_PATH, file});
    ASSERT_TRUE(churning.wait_for_stdout("ready\n", 20s)) << churning.err();
    std::this_thread::sleep_for(std::chrono::microseconds(pause_us(random)));  // the moment
    churning.signal(SIGKILL);
    const Finished finished = churning.wait(20s);
    const long answers = answered(finished.out);
    ASSERT_GE(answers, 0) << "kill " << kill << ": " << finished.out;
    const auto loaded = layout::load_layout_file(file);
    ASSERT_TRUE(loaded) << "kill " << kill << " after " << answers
                        << " answered changes: " << loaded.error().reason;
    const auto answered_count = static_cast<std::size_t>(answers);
    if (*loaded == expected.after(answered_count)) {
      ++found_answered;
    } else {
      ASSERT_EQ(*loaded, expected.after(answered_count + 1))
          << "kill " << kill << " after " << answers << " answered changes:\n"
          << layout::to_yaml(*loaded);
      ++found_unanswered;
    }
    changes += answered_count;
    // At most the one save the kill interrupted, and the owner's next start removes it.
    const std::size_t left = leftovers(dir.path());
    ASSERT_LE(left, 1u) << "kill " << kill;
    unfinished += left;
    EXPECT_EQ(layout::remove_unfinished_saves(file), left);
    EXPECT_EQ(leftovers(dir.path()), 0u);
  }
  // The figures for the closing note and docs/layout.md.
  std::printf(
      "%d kills after %zu answered changes in all: the file held the last answered "
      "change %d times, the next one (saved, unanswered) %d times; %zu unfinished saves "
      "left beside it\n",
      kKills, changes, found_answered, found_unanswered, unfinished);
  EXPECT_EQ(found_answered + found_unanswered, kKills);
}

}  // namespace
}  // namespace teejet::testing
