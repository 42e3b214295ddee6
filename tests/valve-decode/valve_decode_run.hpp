#pragma once

// Running the built valve-decode as a user would, and comparing its output line by line: what
// the candump and the MCAP suites share. VALVE_DECODE_PATH names the binary (CMake).

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "support/subprocess.hpp"

namespace teejet::testing::valve_decode {

inline std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// valve-decode with `arguments`, reading `input` on standard input.
inline Finished run_valve_decode(std::vector<std::string> arguments,
                                 const std::string& input = "") {
  arguments.insert(arguments.begin(), VALVE_DECODE_PATH);
  Subprocess valve_decode(arguments, Subprocess::Input::kPipe);
  valve_decode.write_input(input);
  valve_decode.close_input();
  auto finished = valve_decode.wait(std::chrono::seconds(30));
  EXPECT_FALSE(finished.timed_out) << "valve-decode did not exit";
  return finished;
}

// Compares line by line so that a failure names the line, not a wall of text.
inline void expect_same_lines(const std::string& actual, const std::string& expected) {
  const auto actual_lines = lines_of(actual);
  const auto expected_lines = lines_of(expected);
  for (std::size_t i = 0; i < std::min(actual_lines.size(), expected_lines.size()); ++i) {
    EXPECT_EQ(actual_lines[i], expected_lines[i]) << "output line " << i + 1;
  }
  EXPECT_EQ(actual_lines.size(), expected_lines.size()) << actual;
}

}  // namespace teejet::testing::valve_decode
