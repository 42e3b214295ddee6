// Runs the built valve-decode binary as a user would, on files and on standard input.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "support/scratch_dir.hpp"
#include "support/subprocess.hpp"
#include "valve_decode_run.hpp"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using teejet::testing::Finished;
using teejet::testing::ScratchDir;
using teejet::testing::Subprocess;
using teejet::testing::valve_decode::expect_same_lines;
using teejet::testing::valve_decode::lines_of;
using teejet::testing::valve_decode::read_file;
using teejet::testing::valve_decode::run_valve_decode;

constexpr const char* kValveDecode = VALVE_DECODE_PATH;
constexpr const char* kSampleLog = SAMPLE_LOG_PATH;
constexpr const char* kSampleExpected = SAMPLE_EXPECTED_PATH;

bool is_json(const std::string& text) { return nlohmann::json::accept(text); }

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
  Subprocess valve_decode({kValveDecode}, Subprocess::Input::kPipe);
  valve_decode.write_input("(1700000000.000123) can0 18EFD8D5#04\n");
  // Standard input stays open: the answer must come while valve-decode waits for more.
  valve_decode.wait_for_stdout("\n", 10s);
  const std::string received = valve_decode.out();
  valve_decode.close_input();
  const auto finished = valve_decode.wait(30s);
  EXPECT_FALSE(finished.timed_out) << "valve-decode did not exit";
  EXPECT_EQ(finished.exit_code, 0);
  EXPECT_EQ(received, R"({"t":1700000000.000123,"iface":"can0","dir":"to_valve","addr":216,)"
                      R"("msg":"clear_errors","fields":{}})"
                      "\n");
  EXPECT_EQ(finished.out, received) << "nothing more at the end of the input";
}

TEST(ValveDecodeEndToEnd, HelpExplainsTheFormat) {
  const auto run = run_valve_decode({"--help"});
  EXPECT_EQ(run.exit_code, 0);
  for (const char* text : {"candump -L", R"("t":1700000000.000123)", R"({"error":)",
                           "Blank lines are skipped", "standard input", "Exit status"}) {
    EXPECT_NE(run.out.find(text), std::string::npos) << text;
  }
}

// valve-decode through /bin/sh, for standard inputs a test cannot give it otherwise.
Finished run_with_redirection(const std::string& redirection) {
  auto finished =
      teejet::testing::run({"/bin/sh", "-c", "exec \"$0\" " + redirection, kValveDecode});
  EXPECT_FALSE(finished.timed_out) << "valve-decode did not exit";
  return finished;
}

TEST(ValveDecodeEndToEnd, StandardInputThatIsADirectoryIsAReadError) {
  ScratchDir dir;
  const auto run = run_with_redirection("< '" + dir.path().string() + "'");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_EQ(run.out, "");
  EXPECT_EQ(run.err, "valve-decode: error reading standard input: Is a directory\n");
}

TEST(ValveDecodeEndToEnd, ClosedStandardInputIsAReadError) {
  const auto run = run_with_redirection("<&-");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_EQ(run.out, "");
  EXPECT_EQ(run.err, "valve-decode: error reading standard input: Bad file descriptor\n");
}

TEST(ValveDecodeEndToEnd, AnUnreadableStandardInputStillLetsTheFilesDecode) {
  const auto run = run_with_redirection("'" + std::string(kSampleLog) + "' - '" +
                                        std::string(kSampleLog) + "' <&-");
  EXPECT_EQ(run.exit_code, 1);
  expect_same_lines(run.out, read_file(kSampleExpected) + read_file(kSampleExpected));
  EXPECT_EQ(run.err, "valve-decode: error reading standard input: Bad file descriptor\n");
}

TEST(ValveDecodeEndToEnd, AnEmptyFileNameCannotBeOpened) {
  const auto run = run_valve_decode({"", kSampleLog});
  EXPECT_EQ(run.exit_code, 1);
  expect_same_lines(run.out, read_file(kSampleExpected));
  EXPECT_NE(run.err.find("cannot open ''"), std::string::npos) << run.err;
}

// The documented usage status, not CLI11's internal code (109 for an unknown option).
// valve-decode has no option that takes a value: unknown options are the only bad command line.
TEST(ValveDecodeEndToEnd, UnknownOptionsExitTwoAndSayWhich) {
  for (const char* option : {"--no-such-option", "-x", "--json"}) {
    const auto run = run_valve_decode({option, kSampleLog});
    EXPECT_EQ(run.exit_code, 2) << option;
    EXPECT_EQ(run.out, "") << option;
    EXPECT_NE(run.err.find(option), std::string::npos) << run.err;
  }
}

TEST(ValveDecodeEndToEnd, VersionExitsZero) {
  const auto run = run_valve_decode({"--version"});
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_EQ(run.out.rfind("valve-decode ", 0), 0u) << run.out;
}

}  // namespace
