#pragma once

// Whether a participant's Fast DDS event thread still runs. That one thread runs every timer of
// the participant: its announcements, its writers' heartbeats, the lease checks of the others.
// Fast DDS 2.9.1 (and up to 2.14 at least) can deadlock it for good: a receive thread that
// removes a remote writer holds the discovery lock while it waits for the event thread to finish
// a timer of that writer's proxy, and the event thread's next timer (a lease check, a liveliness
// assertion) waits for the discovery lock (docs/topics.md, "A participant that stops"). The
// participant then goes deaf and silent, and deleting it waits forever.
//
// The beat: a writer of its own, written once and never again, with a deadline of `period`; the
// event thread tells its listener of each missed deadline. Silence for `stalled_after` calls
// `on_stalled` once, on the watchdog's own thread.

#include <atomic>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "teejet/core/result.hpp"
#include "teejet/core/time.hpp"
#include "teejet/dds/participant.hpp"

namespace teejet::dds {

struct EventWatchdogOptions {
  Duration period = std::chrono::seconds(1);
  // Far above what a starved machine delays the thread by (a few seconds at a load of 100).
  Duration stalled_after = std::chrono::seconds(30);
  std::function<void(Duration silent_for)> on_stalled;
};

class EventWatchdog {
 public:
  // An Error names the topic and, under DDS-Security, the permission it needs.
  static Result<std::unique_ptr<EventWatchdog>> create(Participant& participant,
                                                       EventWatchdogOptions options);
  // What a program says of a stall, for its log.
  static std::string describe(Duration silent_for);
  // Stops watching and deletes the writer (which waits for the event thread: a watchdog that
  // reported a stall must not be destroyed; the process ends instead).
  ~EventWatchdog();

  // Leaves the writer to the participant's deletion and goes on watching through it: a
  // deletion that takes `stalled_after` from the last beat is reported as a stall (the
  // participant's deletion waits for the event thread too). Destroy the watchdog after the
  // participant then: its writer's listener is this object.
  void outlive_participant();
  EventWatchdog(const EventWatchdog&) = delete;
  EventWatchdog& operator=(const EventWatchdog&) = delete;

  std::uint64_t beats() const { return beats_.load(); }
  // Whether a stall was reported (set before on_stalled is called).
  bool stalled() const { return stalled_.load(); }

 private:
  class Listener;

  EventWatchdog(Participant& participant, EventWatchdogOptions options);
  void beat();
  void watch(std::stop_token stop);

  Participant& participant_;
  const EventWatchdogOptions options_;
  std::unique_ptr<Listener> listener_;
  eprosima::fastdds::dds::DataWriter* writer_ = nullptr;
  std::atomic<std::uint64_t> beats_{0};
  std::atomic<bool> stalled_{false};
  std::atomic<std::chrono::steady_clock::rep> last_beat_;
  std::mutex mutex_;
  std::condition_variable_any wake_;
  std::jthread watcher_;
};

}  // namespace teejet::dds
