// valvectl: lists, watches and commands TeeJet CAN valves through teejet-gateway over DDS.

#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <fastdds/dds/log/Log.hpp>
#include <iostream>

#include "cli.hpp"
#include "exit_codes.hpp"
#include "session.hpp"
#include "teejet/stop_signals.hpp"

// AddressSanitizer (gcc says so by a macro, clang by a feature) checks for leaks at exit.
#if defined(__SANITIZE_ADDRESS__)
#define LEAK_CHECK_AT_EXIT 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define LEAK_CHECK_AT_EXIT 1
#endif
#endif

namespace {

std::atomic<bool> interrupted{false};

}  // namespace

int main(int argc, char** argv) {
  using namespace teejet::valvectl;
  const ParseOutcome parsed = parse_command_line(argc, argv);
  std::cout << parsed.out << std::flush;
  std::cerr << parsed.err << std::flush;
  if (!parsed.invocation) return parsed.exit_code;

  teejet::command_line::stop_on_sigint_or_sigterm(interrupted,
                                                  teejet::command_line::SecondSignal::kEndsAtOnce);
  const int exit_code = run(*parsed.invocation, {.out = std::cout,
                                                 .err = std::cerr,
                                                 .out_is_tty = ::isatty(STDOUT_FILENO) == 1,
                                                 .interrupted = interrupted});
  std::cout.flush();
  const int status = std::cout ? exit_code : kExitFailure;
  if (!std::cout) std::cerr << "valvectl: error writing the output\n";
    // Fast DDS 2.9's participant factory sleeps 100 ms in its destructor at exit: a third of a
    // late `valvectl list`. The participant is deleted by now (run() owns it) and the output
    // written, so leave without the static destructors, Fast DDS's own log lines flushed first.
#if !defined(LEAK_CHECK_AT_EXIT)
  eprosima::fastdds::dds::Log::Flush();
  std::fflush(nullptr);
  std::_Exit(status);
#else
  return status;
#endif
}
