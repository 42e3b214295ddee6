// valvectl: lists, watches and commands TeeJet CAN valves through teejet-gateway over DDS.

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <iostream>

#include "cli.hpp"
#include "exit_codes.hpp"
#include "session.hpp"

namespace {

std::atomic<bool> interrupted{false};

void on_signal(int) { interrupted = true; }

void install_signal_handlers() {
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  // A second Ctrl-C kills at once, should a wait ever not notice the first.
  action.sa_flags = static_cast<int>(SA_RESETHAND);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace teejet::valvectl;
  const ParseOutcome parsed = parse_command_line(argc, argv);
  std::cout << parsed.out << std::flush;
  std::cerr << parsed.err << std::flush;
  if (!parsed.invocation) return parsed.exit_code;

  install_signal_handlers();
  const int exit_code = run(*parsed.invocation, {.out = std::cout,
                                                 .err = std::cerr,
                                                 .out_is_tty = ::isatty(STDOUT_FILENO) == 1,
                                                 .interrupted = interrupted});
  std::cout.flush();
  if (!std::cout) {
    std::cerr << "valvectl: error writing the output\n";
    return kExitFailure;
  }
  return exit_code;
}
