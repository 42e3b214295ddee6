// Runs the built valve-sim binary as a user would: usage errors, a bus that cannot be opened,
// signals. SocketCAN itself is exercised in the UML bench (tests/uml/sim).

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <fstream>
#include <string>
#include <vector>

#include "support/scratch_dir.hpp"
#include "support/subprocess.hpp"

namespace {

using namespace std::chrono_literals;
using teejet::testing::Finished;
using teejet::testing::ScratchDir;
using teejet::testing::Subprocess;

constexpr const char* kValveSim = VALVE_SIM_PATH;
// Each step (starting, logging a change, exiting after a signal) gets this long of its own.
constexpr auto kStep = 10s;

Subprocess start(std::vector<std::string> args) {
  args.insert(args.begin(), kValveSim);
  return Subprocess(args);
}

// Waits until valve-sim's log (stderr) contains `text`.
bool logs(Subprocess& sim, const std::string& text) {
  return sim.wait_for_stderr(text, sim.elapsed() + kStep);
}

Finished exits(Subprocess& sim) {
  auto finished = sim.wait(sim.elapsed() + kStep);
  EXPECT_FALSE(finished.timed_out) << "valve-sim did not exit";
  return finished;
}

Finished run(std::vector<std::string> args) {
  auto sim = start(std::move(args));
  return exits(sim);
}

void expect_usage_error(const std::vector<std::string>& args, const std::string& message) {
  const auto result = run(args);
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find(message), std::string::npos) << result.err;
}

TEST(SimCli, HelpDescribesTheFlags) {
  const auto result = run({"--help"});
  EXPECT_EQ(result.exit_code, 0);
  for (const auto* flag : {"--can", "--valves", "--serials", "--dps", "--closed", "--opened",
                           "--opening-direction", "--config", "--inject-error", "-v", "SIGUSR1"}) {
    EXPECT_NE(result.out.find(flag), std::string::npos) << flag;
  }
}

TEST(SimCli, UsageErrorsExitTwoAndSayWhy) {
  expect_usage_error({"--valves", "2"}, "--can is required");
  expect_usage_error({"--can", "virtual:x"}, "no valves to simulate");
  expect_usage_error({"--can", "virtual:x", "--valves", "2", "--serials", "5"}, "excludes");
  expect_usage_error({"--can", "virtual:x", "--valves", "33"}, "1 to 32");
  expect_usage_error({"--can", "virtual:x", "--serials", "12x"}, "serial '12x'");
  expect_usage_error({"--can", "virtual:x", "--valves", "1", "--opened", "350"}, "at most 340");
  expect_usage_error({"--can", "virtual:x", "--valves", "1", "--dps", "0"}, "degrees per second");
  expect_usage_error({"--can", "virtual:x", "--valves", "1", "--opening-direction", "left"},
                     "--opening-direction");
  expect_usage_error({"--can", "virtual:x", "--valves", "1", "--inject-error", "1:sparks:1:2"},
                     "unknown error kind 'sparks'");
  expect_usage_error(
      {"--can", "virtual:x", "--valves", "1", "--inject-error", "9:high-voltage:16:15"},
      "TJV000009, which is not a simulated valve");
  expect_usage_error({"--can", "virtual:x", "--config", "/nonexistent/sim.yaml"},
                     "cannot read config file '/nonexistent/sim.yaml'");
}

// The documented 2, not CLI11's internal codes (109 unknown, 105 conversion, 114 missing).
TEST(SimCli, UnknownFlagsBadAndMissingValuesExitTwo) {
  expect_usage_error({"--can", "virtual:x", "--valves", "1", "--no-such-flag"}, "--no-such-flag");
  expect_usage_error({"--can", "virtual:x", "--valves", "many"}, "--valves");
  expect_usage_error({"--can", "virtual:x", "--valves", "-1"}, "--valves");
  expect_usage_error({"--can", "virtual:x", "--valves", "1", "--dps", "fast"}, "--dps");
  expect_usage_error({"--can", "virtual:x", "--valves"}, "--valves");
  expect_usage_error({"--valves", "1", "--can"}, "--can");
  const auto version = run({"--version"});
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_EQ(version.out.rfind("valve-sim ", 0), 0u) << version.out;
}

// CLI11 makes 0 of an empty value: `--closed ""` was a Closed Degrees of 0.
TEST(SimCli, EmptyValuesAreUsageErrorsNamingTheOption) {
  for (const char* option : {"--dps", "--closed", "--opened", "--start", "--opening-direction",
                             "--config", "--inject-error"}) {
    // --opening-direction's list of words speaks first: " not in {clockwise,counterclockwise}".
    expect_usage_error({"--can", "virtual:x", "--valves", "1", option, ""},
                       std::string(option) + ": ");
  }
  expect_usage_error({"--can", "virtual:x", "--valves", "1", "--closed", ""},
                     "--closed: the value is empty");
  expect_usage_error({"--can", "", "--valves", "1"}, "--can: the value is empty");
  expect_usage_error({"--can", "virtual:x", "--valves", ""}, "--valves: the value is empty");
  expect_usage_error({"--can", "virtual:x", "--serials", ""}, "--serials: the value is empty");
}

TEST(SimCli, NotANumberOrInfiniteSettingsAreRefused) {
  for (const char* option : {"--dps", "--closed", "--opened", "--start"}) {
    for (const char* value : {"nan", "inf", "1e400"}) {
      const auto result = run({"--can", "virtual:x", "--valves", "1", option, value});
      EXPECT_EQ(result.exit_code, 2) << option << ' ' << value << ": " << result.err;
    }
  }
}

TEST(SimCli, ConfigFileMistakesExitTwoWithTheLine) {
  ScratchDir dir;
  const auto path = dir / "sim.yaml";
  std::ofstream(path) << "valves:\n  - serial: 1\n    opend: 90\n";
  expect_usage_error({"--can", "virtual:x", "--config", path.string()},
                     "sim.yaml:3: valves[0]: unknown key 'opend'");
}

TEST(SimCli, ABusThatCannotOpenExitsOneAndSaysWhy) {
  const auto result = run({"--can", "teejet-no-such-can0", "--valves", "1"});
  EXPECT_EQ(result.exit_code, 1) << result.err;
  EXPECT_NE(result.err.find("cannot open teejet-no-such-can0"), std::string::npos) << result.err;
}

TEST(SimCli, RunsUntilSigtermOrSigintAndExitsZero) {
  for (const int number : {SIGTERM, SIGINT}) {
    auto sim = start({"--can", "virtual:cli-signal", "--valves", "2"});
    ASSERT_TRUE(logs(sim, "simulating 2 valve(s)")) << sim.err();
    sim.signal(number);
    const auto finished = exits(sim);
    EXPECT_EQ(finished.exit_code, 0) << finished.err;
    EXPECT_NE(finished.err.find("stopping"), std::string::npos) << finished.err;
  }
}

TEST(SimCli, Sigusr1AddsAValveThatTakesTheFirstAddress) {
  auto sim = start({"--can", "virtual:cli-usr1", "--serials", "123456,TJV123457"});
  ASSERT_TRUE(logs(sim, "simulating 2 valve(s)")) << sim.err();
  sim.signal(SIGUSR1);
  EXPECT_TRUE(logs(sim, "TJV123455 added at 0xD8")) << sim.err();
  EXPECT_TRUE(logs(sim, "TJV123457 moves from 0xD9 to 0xDA")) << sim.err();
  sim.signal(SIGTERM);
  EXPECT_EQ(exits(sim).exit_code, 0);
}

TEST(SimCli, Sigusr1TakesHotplugValvesFromTheConfigFileFirst) {
  ScratchDir dir;
  const auto path = dir / "sim.yaml";
  std::ofstream(path) << "hotplug:\n  - serial: 2\n    errors:\n"
                         "      - {kind: high-voltage, value: 16.2, limit: 15.5}\n";
  auto sim = start({"--can", "virtual:cli-hotplug", "--serials", "1,3", "--config", path.string()});
  ASSERT_TRUE(logs(sim, "simulating 2 valve(s)")) << sim.err();
  sim.signal(SIGUSR1);
  EXPECT_TRUE(logs(sim, "TJV000002 added at 0xD9")) << sim.err();
  EXPECT_TRUE(logs(sim, "TJV000002: high_voltage error latched")) << sim.err();
  sim.signal(SIGUSR1);  // the list is used up: one below the lowest
  EXPECT_TRUE(logs(sim, "TJV000000 added at 0xD8")) << sim.err();
  sim.signal(SIGINT);
  EXPECT_EQ(exits(sim).exit_code, 0);
}

}  // namespace
