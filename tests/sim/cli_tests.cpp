// Runs the built valve-sim binary as a user would: usage errors, a bus that cannot be opened,
// signals. SocketCAN itself is exercised in the UML bench (tests/uml/sim).

#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

constexpr const char* kValveSim = VALVE_SIM_PATH;

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

class ScratchDir {
 public:
  ScratchDir() {
    static std::atomic<int> counter{0};
    path_ = fs::path(testing::TempDir()) /
            ("valve_sim_cli_" + std::to_string(getpid()) + "_" + std::to_string(counter++));
    fs::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// valve-sim with stdout and stderr in files of the scratch directory.
class Process {
 public:
  Process(const ScratchDir& dir, std::vector<std::string> args)
      : out_(dir.path() / "stdout"), err_(dir.path() / "stderr") {
    args.insert(args.begin(), kValveSim);
    std::vector<char*> argv;
    for (auto& arg : args) argv.push_back(arg.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 1, out_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, 2, err_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    spawned_ = posix_spawn(&pid_, kValveSim, &actions, nullptr, argv.data(), environ) == 0;
    posix_spawn_file_actions_destroy(&actions);
  }
  ~Process() {
    if (spawned_ && !exit_code_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

  bool spawned() const { return spawned_; }
  void signal(int number) const { kill(pid_, number); }

  // The exit code (128 + n after signal n); nullopt if it is still running at the deadline.
  std::optional<int> wait(std::chrono::milliseconds within = 10s) {
    const auto deadline = std::chrono::steady_clock::now() + within;
    while (!exit_code_) {
      int status = 0;
      const pid_t done = waitpid(pid_, &status, WNOHANG);
      if (done == pid_) {
        exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      } else if (std::chrono::steady_clock::now() >= deadline) {
        return std::nullopt;
      } else {
        std::this_thread::sleep_for(5ms);
      }
    }
    return exit_code_;
  }

  // Waits until stderr contains `text`.
  bool wait_for_log(const std::string& text, std::chrono::milliseconds within = 10s) const {
    const auto deadline = std::chrono::steady_clock::now() + within;
    while (std::chrono::steady_clock::now() < deadline) {
      if (err().find(text) != std::string::npos) return true;
      std::this_thread::sleep_for(10ms);
    }
    return false;
  }

  std::string out() const { return read_file(out_); }
  std::string err() const { return read_file(err_); }

 private:
  fs::path out_;
  fs::path err_;
  pid_t pid_ = 0;
  bool spawned_ = false;
  std::optional<int> exit_code_;
};

struct Run {
  int code;
  std::string out;
  std::string err;
};

Run run(std::vector<std::string> args) {
  ScratchDir dir;
  Process process(dir, std::move(args));
  EXPECT_TRUE(process.spawned());
  const auto code = process.wait();
  EXPECT_TRUE(code) << "valve-sim did not exit";
  return {code.value_or(-1), process.out(), process.err()};
}

void expect_usage_error(const std::vector<std::string>& args, const std::string& message) {
  const auto result = run(args);
  EXPECT_EQ(result.code, 2) << result.err;
  EXPECT_NE(result.err.find(message), std::string::npos) << result.err;
}

TEST(SimCli, HelpDescribesTheFlags) {
  const auto result = run({"--help"});
  EXPECT_EQ(result.code, 0);
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

TEST(SimCli, ConfigFileMistakesExitTwoWithTheLine) {
  ScratchDir dir;
  const auto path = dir.path() / "sim.yaml";
  std::ofstream(path) << "valves:\n  - serial: 1\n    opend: 90\n";
  expect_usage_error({"--can", "virtual:x", "--config", path.string()},
                     "sim.yaml:3: valves[0]: unknown key 'opend'");
}

TEST(SimCli, ABusThatCannotOpenExitsOneAndSaysWhy) {
  const auto result = run({"--can", "teejet-no-such-can0", "--valves", "1"});
  EXPECT_EQ(result.code, 1) << result.err;
  EXPECT_NE(result.err.find("cannot open teejet-no-such-can0"), std::string::npos) << result.err;
}

TEST(SimCli, RunsUntilSigtermOrSigintAndExitsZero) {
  for (const int number : {SIGTERM, SIGINT}) {
    ScratchDir dir;
    Process process(dir, {"--can", "virtual:cli-signal", "--valves", "2"});
    ASSERT_TRUE(process.spawned());
    ASSERT_TRUE(process.wait_for_log("simulating 2 valve(s)")) << process.err();
    process.signal(number);
    EXPECT_EQ(process.wait(), std::optional<int>(0)) << process.err();
    EXPECT_NE(process.err().find("stopping"), std::string::npos) << process.err();
  }
}

TEST(SimCli, Sigusr1AddsAValveThatTakesTheFirstAddress) {
  ScratchDir dir;
  Process process(dir, {"--can", "virtual:cli-usr1", "--serials", "123456,TJV123457"});
  ASSERT_TRUE(process.spawned());
  ASSERT_TRUE(process.wait_for_log("simulating 2 valve(s)")) << process.err();
  process.signal(SIGUSR1);
  EXPECT_TRUE(process.wait_for_log("TJV123455 added at 0xD8")) << process.err();
  EXPECT_TRUE(process.wait_for_log("TJV123457 moves from 0xD9 to 0xDA")) << process.err();
  process.signal(SIGTERM);
  EXPECT_EQ(process.wait(), std::optional<int>(0));
}

TEST(SimCli, Sigusr1TakesHotplugValvesFromTheConfigFileFirst) {
  ScratchDir dir;
  const auto path = dir.path() / "sim.yaml";
  std::ofstream(path) << "hotplug:\n  - serial: 2\n    errors:\n"
                         "      - {kind: high-voltage, value: 16.2, limit: 15.5}\n";
  Process process(dir,
                  {"--can", "virtual:cli-hotplug", "--serials", "1,3", "--config", path.string()});
  ASSERT_TRUE(process.spawned());
  ASSERT_TRUE(process.wait_for_log("simulating 2 valve(s)")) << process.err();
  process.signal(SIGUSR1);
  EXPECT_TRUE(process.wait_for_log("TJV000002 added at 0xD9")) << process.err();
  EXPECT_TRUE(process.wait_for_log("TJV000002: high-voltage error latched")) << process.err();
  process.signal(SIGUSR1);  // the list is used up: one below the lowest
  EXPECT_TRUE(process.wait_for_log("TJV000000 added at 0xD8")) << process.err();
  process.signal(SIGINT);
  EXPECT_EQ(process.wait(), std::optional<int>(0));
}

}  // namespace
