#pragma once

// Runs a program with its standard output and error captured, for end-to-end tests of tools.

#include <sys/types.h>

#include <chrono>
#include <string>
#include <vector>

namespace teejet::testing {

struct Finished {
  int exit_code = -1;  // -1: killed at the time limit, or ended by a signal
  std::string out;
  std::string err;
  std::chrono::milliseconds took{};
};

class Subprocess {
 public:
  // Starts argv[0] with the test's environment; throws std::runtime_error when it cannot.
  explicit Subprocess(const std::vector<std::string>& argv);
  ~Subprocess();  // kills a child that is still running
  Subprocess(const Subprocess&) = delete;
  Subprocess& operator=(const Subprocess&) = delete;

  // Reads the output until its standard output contains `part`; false when `limit` (counted
  // from the start) passes first or the output ends without it.
  bool wait_for_output(const std::string& part, std::chrono::milliseconds limit);

  void signal(int signal_number);

  // Reads the output to its end and reaps the child; kills it when `limit` (counted from the
  // start) passes first.
  Finished wait(std::chrono::milliseconds limit);

 private:
  // Reads what is available, waiting until `until` at most; false when both pipes are closed.
  bool pump(std::chrono::steady_clock::time_point until);

  pid_t pid_ = -1;
  int out_fd_ = -1;
  int err_fd_ = -1;
  std::chrono::steady_clock::time_point started_;
  Finished finished_;
};

// Starts and waits in one go.
Finished run(const std::vector<std::string>& argv,
             std::chrono::milliseconds limit = std::chrono::seconds(30));

}  // namespace teejet::testing
