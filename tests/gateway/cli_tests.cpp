// Runs the built teejet-gateway as an operator or a supervisor would: bad command lines exit 2
// (not CLI11's internal codes), and every signal that ends it goes through the safe stop with
// the exit status docs/gateway.md gives. The Stop frames themselves are watched on a real vcan0
// in tests/uml/gateway/gateway_signals.sh; here the gateway runs its own simulated valves.
// Inside a private network namespace (tests/netns/isolated): the gateway joins DDS.

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <string>
#include <vector>

#include "support/subprocess.hpp"
#include "support/test_domain.hpp"

namespace {

using namespace std::chrono_literals;
using teejet::testing::Finished;
using teejet::testing::Subprocess;

constexpr const char* kGateway = TEEJET_GATEWAY_PATH;
// Each step (starting, stopping after a signal) gets this long of its own.
constexpr auto kStep = 20s;

Finished run_gateway(std::vector<std::string> args) {
  args.insert(args.begin(), kGateway);
  auto finished = teejet::testing::run(args, kStep);
  EXPECT_FALSE(finished.timed_out) << "teejet-gateway did not exit";
  return finished;
}

void expect_usage_error(const std::vector<std::string>& args, const std::string& message) {
  const auto finished = run_gateway(args);
  EXPECT_EQ(finished.exit_code, 2) << finished.out << finished.err;
  EXPECT_NE((finished.out + finished.err).find(message), std::string::npos)
      << finished.out << finished.err;
}

TEST(GatewayCommandLine, UnknownFlagsBadAndMissingValuesExitTwo) {
  expect_usage_error({"--can", "sim:1", "--no-such-flag"}, "--no-such-flag");
  expect_usage_error({"--can", "sim:1", "--domain", "seven"}, "--domain");
  expect_usage_error({"--can", "sim:1", "--domain", "233"}, "--domain");
  expect_usage_error({"--can", "sim:1", "--log-level", "loud"}, "--log-level");
  expect_usage_error({"--can", "sim:1", "--domain"}, "--domain");
  expect_usage_error({"--can"}, "--can");
  expect_usage_error({"--config", "/nonexistent/gateway.yaml"}, "--config");
  expect_usage_error({}, "no CAN bus");
}

// CLI11 makes 0 of an empty value: `--domain ""` joined domain 0.
TEST(GatewayCommandLine, EmptyValuesAreUsageErrorsNamingTheOption) {
  for (const char* option :
       {"--can", "--domain", "--profile", "--config", "--name", "--log-level"}) {
    std::vector<std::string> args{option, ""};
    if (std::string(option) != "--can") args.insert(args.end(), {"--can", "sim:1"});
    // The range, file and word checks of --domain, --profile, --config and --log-level speak first.
    expect_usage_error(args, std::string(option) + ": ");
  }
  expect_usage_error({"--can", "sim:1", "--name", ""}, "--name: the value is empty");
}

// The name keys teejet/gateway/status (string<64>): a longer one would be published cut, and
// two long names with a common start would become one gateway.
TEST(GatewayCommandLine, ANameLongerThanTheStatusKeyIsRefused) {
  const std::string longest(64, 'g');
  expect_usage_error({"--can", "sim:1", "--name", longest + "h"},
                     "the gateway name \"" + longest +
                         "h\" is 65 characters long; it must be 1 "
                         "to 64");
}

TEST(GatewayCommandLine, HelpAndVersionExitZero) {
  const auto help = run_gateway({"--help"});
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("--keep-valves-running"), std::string::npos) << help.out;
  const auto version = run_gateway({"--version"});
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_EQ(version.out.rfind("teejet-gateway ", 0), 0u) << version.out;
}

// teejet-gateway with two simulated valves; up() once it says it runs.
Subprocess gateway_process() {
  return Subprocess(
      {kGateway, "--can", "sim:2", "--domain", std::to_string(teejet::testing::test_domain())});
}
bool up(Subprocess& gateway) { return gateway.wait_for_stdout("in DDS domain", kStep); }

// Waits for the gateway to end after `name`, and checks it went through the safe stop.
void expect_safe_stop(Subprocess& gateway, const std::string& name, int exit_status) {
  const auto finished = gateway.wait(gateway.elapsed() + kStep);
  ASSERT_FALSE(finished.timed_out);
  EXPECT_EQ(finished.exit_code, exit_status) << finished.err;
  EXPECT_NE(finished.out.find(name + ": shutting down"), std::string::npos) << finished.out;
  EXPECT_NE(finished.out.find("valve(s) on exit"), std::string::npos) << finished.out;
}

struct Ending {
  int signal;
  const char* name;
  int exit_status;
};

// Asked to stop (SIGTERM, SIGINT): 0. Anything else that can be caught: 128 + n, as a shell
// reports a death by that signal, after the same safe stop.
TEST(GatewaySignals, EverySignalThatEndsTheGatewayStopsTheValvesFirst) {
  for (const Ending ending :
       {Ending{SIGTERM, "SIGTERM", 0}, Ending{SIGINT, "SIGINT", 0}, Ending{SIGHUP, "SIGHUP", 129},
        Ending{SIGQUIT, "SIGQUIT", 131}, Ending{SIGUSR1, "SIGUSR1", 138},
        Ending{SIGUSR2, "SIGUSR2", 140}, Ending{SIGALRM, "SIGALRM", 142}}) {
    SCOPED_TRACE(ending.name);
    auto gateway = gateway_process();
    ASSERT_TRUE(up(gateway)) << gateway.out() << gateway.err();
    gateway.signal(ending.signal);
    expect_safe_stop(gateway, ending.name, ending.exit_status);
  }
}

// SIGPIPE is ignored: a log nobody reads any more must not end the gateway. Had it ended it,
// the SIGTERM after it would find a process killed by SIGPIPE.
TEST(GatewaySignals, ABrokenPipeDoesNotEndTheGateway) {
  auto gateway = gateway_process();
  ASSERT_TRUE(up(gateway)) << gateway.out() << gateway.err();
  gateway.signal(SIGPIPE);
  gateway.signal(SIGTERM);
  expect_safe_stop(gateway, "SIGTERM", 0);
}

}  // namespace
