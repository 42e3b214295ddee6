// Runs the built valve-decode binary as a user would, on files and on standard input.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

constexpr const char* kValveDecode = VALVE_DECODE_PATH;
constexpr const char* kSampleLog = SAMPLE_LOG_PATH;
constexpr const char* kSampleExpected = SAMPLE_EXPECTED_PATH;

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_file(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

bool is_json(const std::string& text) { return nlohmann::json::accept(text); }

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// A directory of its own per use; ctest may run these tests in parallel.
class ScratchDir {
 public:
  ScratchDir() {
    static std::atomic<int> counter{0};
    path_ = fs::path(testing::TempDir()) /
            ("valve_decode_e2e_" + std::to_string(getpid()) + "_" + std::to_string(counter++));
    fs::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  fs::path operator/(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

std::vector<char*> argv_of(std::vector<std::string>& arguments) {
  std::vector<char*> argv;
  for (auto& argument : arguments) argv.push_back(argument.data());
  argv.push_back(nullptr);
  return argv;
}

struct Run {
  int exit_code = -1;
  std::string out;
  std::string err;
};

int wait_for_exit(pid_t pid) {
  int status = 0;
  if (waitpid(pid, &status, 0) != pid) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

Run run_valve_decode(std::vector<std::string> arguments, const std::string& input = "") {
  ScratchDir dir;
  const auto stdin_path = (dir / "stdin").string();
  const auto stdout_path = (dir / "stdout").string();
  const auto stderr_path = (dir / "stderr").string();
  write_file(stdin_path, input);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, stdin_path.c_str(), O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, stdout_path.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, stderr_path.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  arguments.insert(arguments.begin(), kValveDecode);
  auto argv = argv_of(arguments);
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, kValveDecode, &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    ADD_FAILURE() << "cannot start " << kValveDecode;
    return {};
  }
  return Run{wait_for_exit(pid), read_file(stdout_path), read_file(stderr_path)};
}

// Compares line by line so that a failure names the line, not a wall of text.
void expect_same_lines(const std::string& actual, const std::string& expected) {
  const auto actual_lines = lines_of(actual);
  const auto expected_lines = lines_of(expected);
  for (std::size_t i = 0; i < std::min(actual_lines.size(), expected_lines.size()); ++i) {
    EXPECT_EQ(actual_lines[i], expected_lines[i]) << "output line " << i + 1;
  }
  EXPECT_EQ(actual_lines.size(), expected_lines.size());
}

TEST(ValveDecodeEndToEnd, SampleTraceMatchesTheHandWrittenGolden) {
  const auto run = run_valve_decode({kSampleLog});
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_EQ(run.err, "");
  expect_same_lines(run.out, read_file(kSampleExpected));
  EXPECT_EQ(lines_of(run.out).size(), lines_of(read_file(kSampleLog)).size())
      << "one output line per input line";
}

TEST(ValveDecodeEndToEnd, EveryOutputLineIsJsonOfOneOfTheTwoShapes) {
  const auto run = run_valve_decode({kSampleLog});
  const std::vector<std::string> decoded_keys{"t", "iface", "dir", "addr", "msg", "fields"};
  const std::vector<std::string> error_keys{"error", "line"};
  for (const auto& line : lines_of(run.out)) {
    nlohmann::ordered_json json;
    ASSERT_NO_THROW(json = nlohmann::ordered_json::parse(line)) << line;
    ASSERT_TRUE(json.is_object()) << line;
    std::vector<std::string> keys;
    for (const auto& member : json.items()) keys.push_back(member.key());
    EXPECT_TRUE(keys == decoded_keys || keys == error_keys) << line;
    if (keys == decoded_keys) {
      EXPECT_TRUE(json["t"].is_number_float()) << line;
      EXPECT_TRUE(json["addr"].is_number_unsigned()) << line;
      EXPECT_TRUE(json["fields"].is_object()) << line;
    }
  }
}

TEST(ValveDecodeEndToEnd, ReadsStandardInputWhenNoFileIsGiven) {
  const auto run = run_valve_decode({}, read_file(kSampleLog));
  EXPECT_EQ(run.exit_code, 0);
  expect_same_lines(run.out, read_file(kSampleExpected));
}

TEST(ValveDecodeEndToEnd, DashReadsStandardInputInItsTurn) {
  const std::string input = "(1700000009.000001) can0 18EFD8D5#00FFFFFFFFFFFFFF\n";
  const auto run = run_valve_decode({kSampleLog, "-", kSampleLog}, input);
  EXPECT_EQ(run.exit_code, 0);
  const auto expected = read_file(kSampleExpected);
  expect_same_lines(run.out, expected +
                                 R"({"t":1700000009.000001,"iface":"can0","dir":"to_valve",)"
                                 R"("addr":216,"msg":"stop","fields":{}})"
                                 "\n" +
                                 expected);
}

TEST(ValveDecodeEndToEnd, MissingFileExitsOneAfterDecodingTheOthers) {
  const auto run =
      run_valve_decode({"/nonexistent/first.log", kSampleLog, "/nonexistent/second.log"});
  EXPECT_EQ(run.exit_code, 1);
  expect_same_lines(run.out, read_file(kSampleExpected));
  EXPECT_NE(run.err.find("cannot open '/nonexistent/first.log'"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("cannot open '/nonexistent/second.log'"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("No such file or directory"), std::string::npos) << run.err;
}

TEST(ValveDecodeEndToEnd, UnreadableFileExitsOne) {
  ScratchDir dir;
  fs::create_directories(dir / "a_directory");
  const auto directory = (dir / "a_directory").string();
  const auto run = run_valve_decode({directory, kSampleLog});
  EXPECT_EQ(run.exit_code, 1);
  expect_same_lines(run.out, read_file(kSampleExpected));
  EXPECT_NE(run.err.find(directory), std::string::npos) << run.err;
}

TEST(ValveDecodeEndToEnd, TimestampsKeepTheLoggedDigits) {
  // Each of these comes out differently when printed from a double.
  const auto run = run_valve_decode({},
                                    "(1700000000.000193) can0 18EFD8D5#04\n"
                                    "(1700000000.002967) can0 18EFD8D5#04\n"
                                    "(1700000000.000120) can0 18EFD8D5#04\n"
                                    "(1700000001.000000) can0 18EFD8D5#04\n"
                                    "(0000000001.000444) can0 18EFD8D5#04\n"
                                    "(0000000000.000001) can0 18EFD8D5#04\n"
                                    "(9999999999.000001) can0 18EFD8D5#04\n");
  const std::vector<std::string> expected{
      "1700000000.000193", "1700000000.002967", "1700000000.000120", "1700000001.000000",
      "1.000444",          "0.000001",          "9999999999.000001"};
  const auto lines = lines_of(run.out);
  ASSERT_EQ(lines.size(), expected.size()) << run.out;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    EXPECT_EQ(lines[i].rfind("{\"t\":" + expected[i] + ",\"iface\":\"can0\"", 0), 0u) << lines[i];
    EXPECT_TRUE(is_json(lines[i])) << lines[i];
  }
}

TEST(ValveDecodeEndToEnd, BlankLinesAreSkippedAndLineEndingsDropped) {
  const auto run = run_valve_decode({},
                                    "\n   \n\t\r\n(1700000000.000123) can0 18EFD8D5#04\r\n"
                                    "not a frame\r\n\n");
  EXPECT_EQ(run.exit_code, 0);
  expect_same_lines(
      run.out, R"({"t":1700000000.000123,"iface":"can0","dir":"to_valve","addr":216,)"
               R"("msg":"clear_errors","fields":{}})"
               "\n"
               R"json({"error":"timestamp must be in parentheses, e.g. (1700000000.000123)",)json"
               R"("line":"not a frame"})"
               "\n");
}

TEST(ValveDecodeEndToEnd, LastLineWithoutNewlineIsDecoded) {
  const auto run = run_valve_decode({}, "(1700000000.000123) can0 18EFD8D5#04");
  EXPECT_EQ(lines_of(run.out).size(), 1u) << run.out;
}

TEST(ValveDecodeEndToEnd, InvalidUtf8InALineStillGivesValidJson) {
  const auto run = run_valve_decode({}, "\xFF\xFE garbage \xC3\n");
  EXPECT_EQ(run.exit_code, 0);
  const auto lines = lines_of(run.out);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_TRUE(is_json(lines[0])) << lines[0];
}

// `candump -L can0 | valve-decode` must show each frame as it arrives, not when a buffer fills.
TEST(ValveDecodeEndToEnd, FlushesEachLineReadFromStandardInput) {
  std::array<int, 2> to_child{};
  std::array<int, 2> from_child{};
  ASSERT_EQ(pipe2(to_child.data(), O_CLOEXEC), 0);
  ASSERT_EQ(pipe2(from_child.data(), O_CLOEXEC), 0);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, to_child[0], STDIN_FILENO);
  posix_spawn_file_actions_adddup2(&actions, from_child[1], STDOUT_FILENO);
  std::vector<std::string> arguments{kValveDecode};
  auto argv = argv_of(arguments);
  pid_t pid = 0;
  ASSERT_EQ(posix_spawn(&pid, kValveDecode, &actions, nullptr, argv.data(), environ), 0);
  posix_spawn_file_actions_destroy(&actions);
  close(to_child[0]);
  close(from_child[1]);

  const std::string line = "(1700000000.000123) can0 18EFD8D5#04\n";
  ASSERT_EQ(write(to_child[1], line.data(), line.size()), static_cast<ssize_t>(line.size()));
  // Standard input stays open: the answer must come while valve-decode waits for more.
  std::string received;
  while (received.find('\n') == std::string::npos) {
    pollfd readable{from_child[0], POLLIN, 0};
    if (poll(&readable, 1, 10'000) != 1) break;
    std::array<char, 512> buffer{};
    const auto count = read(from_child[0], buffer.data(), buffer.size());
    if (count <= 0) break;
    received.append(buffer.data(), static_cast<std::size_t>(count));
  }
  close(to_child[1]);
  close(from_child[0]);
  EXPECT_EQ(wait_for_exit(pid), 0);
  EXPECT_EQ(received, R"({"t":1700000000.000123,"iface":"can0","dir":"to_valve","addr":216,)"
                      R"("msg":"clear_errors","fields":{}})"
                      "\n");
}

TEST(ValveDecodeEndToEnd, HelpExplainsTheFormat) {
  const auto run = run_valve_decode({"--help"});
  EXPECT_EQ(run.exit_code, 0);
  for (const char* text : {"candump -L", R"("t":1700000000.000123)", R"({"error":)",
                           "Blank lines are skipped", "standard input", "Exit status"}) {
    EXPECT_NE(run.out.find(text), std::string::npos) << text;
  }
}

TEST(ValveDecodeEndToEnd, UnknownOptionIsAUsageError) {
  const auto run = run_valve_decode({"--no-such-option"});
  EXPECT_NE(run.exit_code, 0);
  EXPECT_EQ(run.out, "");
}

}  // namespace
