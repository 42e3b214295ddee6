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

enum class SecondSignal {
  kIgnored,     // the program is stopping already (a recorder closing its file)
  kEndsAtOnce,  // a second Ctrl-C ends the program at once, should a wait not notice the first
};

// `stop` must outlive the process's main loop (a static). Not a signal handler: a handler runs
// on whichever thread the kernel picks, and under ThreadSanitizer only when that thread next
// enters an intercepted call, so a thread blocked for long holds the signal back (CI saw a
// valvectl watch go on for 15 s after its Ctrl-C).
inline void stop_on_sigint_or_sigterm(std::atomic<bool>& stop,
                                      SecondSignal second = SecondSignal::kIgnored) {
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  std::thread([signals, &stop, second] {
    int number = 0;
    sigwait(&signals, &number);
    stop = true;
    if (second == SecondSignal::kIgnored) return;
    sigwait(&signals, &number);
    // The default action, as if no one had caught it: the shell sees the signal that ended it.
    std::signal(number, SIG_DFL);
    sigset_t again;
    sigemptyset(&again);
    sigaddset(&again, number);
    pthread_sigmask(SIG_UNBLOCK, &again, nullptr);
    std::raise(number);
  }).detach();
}

}  // namespace teejet::command_line
