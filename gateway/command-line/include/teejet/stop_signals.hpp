#pragma once

// SIGINT and SIGTERM as a flag, for programs whose main loop looks at a flag (teejet-record,
// teejet-replay, test helpers). Call it before any other thread starts: the signals are blocked
// in the caller and so in every thread started later (Fast DDS's), and one thread of its own
// takes them with sigwait(), so that no thread is interrupted in the middle of a write.

#include <pthread.h>

#include <atomic>
#include <csignal>
#include <thread>

namespace teejet::command_line {

// `stop` must outlive the process's main loop (a static).
inline void stop_on_sigint_or_sigterm(std::atomic<bool>& stop) {
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  std::thread([signals, &stop] {
    int number = 0;
    sigwait(&signals, &number);
    stop = true;
  }).detach();
}

}  // namespace teejet::command_line
