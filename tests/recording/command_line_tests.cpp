// teejet-record's and teejet-replay's numbers as a user may type them: each has its range, and
// NaN, infinities and numbers beyond it are refused (exit 2, the reason named) before the program
// joins DDS or opens a file. Before: `--rate nan` replayed a file at once reporting "0 late",
// `--wait-for-readers 1e300` waited for ever, `--duration nan` recorded for ever and
// `--duration 1e300` ended at once with an empty file. Inside a private network namespace,
// should a number get through and the program join DDS.

#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <vector>

#include "support/scratch_dir.hpp"
#include "support/subprocess.hpp"
#include "support/text.hpp"

namespace teejet::testing {
namespace {

using namespace std::chrono_literals;

constexpr int kExitUsage = 2;

struct Refusal {
  std::vector<std::string> argv;  // after the program's path
  std::string reason;             // part of what it prints
};

class NumbersOutOfRange : public ::testing::Test {
 protected:
  void SetUp() override { std::ofstream(file_) << "not read: the command line is refused first"; }

  static void expect_refused(const std::string& program, const Refusal& refusal) {
    std::vector<std::string> argv{program};
    argv.insert(argv.end(), refusal.argv.begin(), refusal.argv.end());
    const Finished finished = run(argv, 30s);
    EXPECT_EQ(finished.exit_code, kExitUsage) << describe(finished);
    EXPECT_TRUE(contains(finished.err, refusal.reason)) << describe(finished);
  }

  ScratchDir scratch_;
  std::string file_ = (scratch_ / "run.mcap").string();
};

TEST_F(NumbersOutOfRange, ReplayRefusesEachWithItsRange) {
  const std::vector<Refusal> refusals{
      {{file_, "--rate", "nan"}, "nan is not a number from 0.001 to 1000"},
      {{file_, "--rate", "inf"}, "inf is not a number from 0.001 to 1000"},
      {{file_, "--rate", "0"}, "0 is not a number from 0.001 to 1000"},
      {{file_, "--rate", "1e300"}, "1e300 is not a number from 0.001 to 1000"},
      {{file_, "--wait-for-readers", "1e300"}, "1e300 is not a number from 0 to 3600"},
      {{file_, "--wait-for-readers", "nan"}, "nan is not a number from 0 to 3600"},
      {{file_, "--start", "nan"}, "nan is not a number from 0 to 3.1536e+07"},
      {{file_, "--start", "-1"}, "-1 is not a number from 0 to 3.1536e+07"},
      {{file_, "--end", "1e300"}, "1e300 is not a number from 0 to 3.1536e+07"},
      {{file_, "--rate", "2x"}, "2x is not a number from 0.001 to 1000"},
  };
  for (const auto& refusal : refusals) expect_refused(TEEJET_REPLAY_PATH, refusal);
}

TEST_F(NumbersOutOfRange, RecordRefusesEachWithItsRange) {
  const std::string output = (scratch_ / "out.mcap").string();
  const std::vector<Refusal> refusals{
      {{"-o", output, "--duration", "nan"}, "nan is not a number from 0.001 to 2.592e+06"},
      {{"-o", output, "--duration", "1e300"}, "1e300 is not a number from 0.001 to 2.592e+06"},
      {{"-o", output, "--duration", "-inf"}, "-inf is not a number from 0.001 to 2.592e+06"},
      {{"-o", output, "--duration", "0"}, "0 is not a number from 0.001 to 2.592e+06"},
  };
  for (const auto& refusal : refusals) expect_refused(TEEJET_RECORD_PATH, refusal);
  EXPECT_FALSE(std::ifstream(output).good()) << "a refused run left " << output;
}

}  // namespace
}  // namespace teejet::testing
