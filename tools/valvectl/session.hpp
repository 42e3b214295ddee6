#pragma once

// Runs one parsed invocation against a DDS domain: discovery, the table, and sending commands
// and following their statuses. Exit statuses: exit_codes.hpp.

#include <atomic>
#include <iosfwd>

#include "cli.hpp"

namespace teejet::valvectl {

struct Terminal {
  std::ostream& out;
  std::ostream& err;
  bool out_is_tty = false;               // watch redraws in place on a terminal
  const std::atomic<bool>& interrupted;  // set by SIGINT/SIGTERM
};

int run(const Invocation& invocation, const Terminal& terminal);

}  // namespace teejet::valvectl
