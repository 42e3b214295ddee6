#pragma once

// Runs a program as a user would, for end-to-end tests of the project's binaries: standard output
// and error captured, standard input from /dev/null or written by the test, signals sent by it.

#include <sys/types.h>

#include <chrono>
#include <string>
#include <string_view>
#include <vector>

namespace teejet::testing {

struct Finished {
  int exit_code = -1;      // -1: ended by a signal, or killed at the time limit
  bool timed_out = false;  // killed at the time limit
  std::string out;
  std::string err;
  std::chrono::milliseconds took{};
};

class Subprocess {
 public:
  // Standard input of the child: /dev/null, or a pipe the test writes with write_input().
  enum class Input { kDevNull, kPipe };
  // Standard output of the child: a pipe, or a terminal (a pseudo-terminal without line
  // translation), as for a person running the program by hand.
  enum class Output { kPipe, kTerminal };

  // Starts argv[0] (a path) with the test's environment; throws std::runtime_error when it cannot.
  explicit Subprocess(const std::vector<std::string>& argv, Input input = Input::kDevNull,
                      Output output = Output::kPipe);
  ~Subprocess();  // kills a child that is still running
  Subprocess(const Subprocess&) = delete;
  Subprocess& operator=(const Subprocess&) = delete;

  // Input::kPipe only. Queues `text` for the child's standard input; it is written while the test
  // waits below, so a child that answers as it reads never blocks on a full pipe.
  void write_input(std::string_view text);
  // Input::kPipe only. End of file for the child once the queued input is written.
  void close_input();

  // Reads the output until standard output (error) contains `part`; false when `limit` (counted
  // from the start) passes first or the output ends without it.
  bool wait_for_stdout(const std::string& part, std::chrono::milliseconds limit);
  bool wait_for_stderr(const std::string& part, std::chrono::milliseconds limit);

  // The output read so far.
  const std::string& out() const { return finished_.out; }
  const std::string& err() const { return finished_.err; }

  // Time since the start, rounded up: a limit of `elapsed() + d` ends `d` from now.
  std::chrono::milliseconds elapsed() const;

  void signal(int signal_number);

  // Reads the output to its end and reaps the child; kills it when `limit` (counted from the
  // start) passes first.
  Finished wait(std::chrono::milliseconds limit);

 private:
  bool wait_for(const std::string& stream, const std::string& part,
                std::chrono::milliseconds limit);
  // Writes queued input and reads what is available, waiting until `until` at most; false when
  // both output pipes are closed.
  bool pump(std::chrono::steady_clock::time_point until);
  void write_pending_input();

  pid_t pid_ = -1;
  int in_fd_ = -1;
  int out_fd_ = -1;
  int err_fd_ = -1;
  bool input_is_pipe_ = false;
  std::string pending_input_;
  bool close_input_when_written_ = false;
  std::chrono::steady_clock::time_point started_;
  Finished finished_;
};

// Exit code, time taken and both outputs, for a failed expectation's message.
std::string describe(const Finished& finished);

// Starts and waits in one go.
Finished run(const std::vector<std::string>& argv,
             std::chrono::milliseconds limit = std::chrono::seconds(30));

}  // namespace teejet::testing
