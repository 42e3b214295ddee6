#pragma once

// valvectl's exit statuses: scripts branch on them, so each outcome has its own number and the
// numbers never change. Documented in docs/valvectl.md.

namespace teejet::valvectl {

enum ExitCode : int {
  kExitOk = 0,
  kExitFailure = 1,       // DDS could not be set up, output could not be written, ...
  kExitNotFound = 2,      // no gateway, or no gateway knows the valve
  kExitRejected = 3,      // the gateway refused the command (REJECTED)
  kExitTimedOut = 4,      // TIMED_OUT, or no status arrived in time
  kExitSuperseded = 5,    // a newer command to the valve replaced this one
  kExitUsage = 64,        // invalid arguments (EX_USAGE); nothing was sent
  kExitInterrupted = 130  // Ctrl-C while waiting for a command (128 + SIGINT)
};

}  // namespace teejet::valvectl
