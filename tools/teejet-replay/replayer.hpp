#pragma once

// teejet-replay's work: a recording's channels as DDS writers, and its messages published again
// with the gaps they were received with (scaled by the rate), each with its recorded source
// timestamp. The caller's thread does it all.

#include <atomic>
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "teejet/core/result.hpp"
#include "teejet/core/time.hpp"
#include "teejet/mcap/reader.hpp"
#include "teejet/recording/clock_steps.hpp"

namespace teejet::replay {

struct ReplayOptions {
  std::string file;
  double rate = 1.0;  // 2: twice as fast
  bool loop = false;
  std::vector<std::string> topics;  // globs on the DDS topic; empty: every teejet topic
  bool with_commands = false;       // teejet/valve/command moves real valves: only when asked
  // Publish even where a live gateway has the name of one in the recording: its state and the
  // recorded one would mix (a dashboard shows a valve jumping between them).
  bool into_live_gateways = false;
  Duration start{};  // offsets from the recording's first message
  std::optional<Duration> end;
  // Before the first message: wait until every replayed topic has a reader, at most this long.
  Duration wait_for_readers = std::chrono::seconds(1);
  int domain = 0;
  std::string profile_file;
};

struct ReplayReport {
  std::uint64_t published = 0;
  std::uint64_t failed = 0;  // writes or disposals the middleware refused
  std::map<std::string, std::uint64_t> per_topic;
  std::string last_failure;
  Duration worst_lateness{};      // how far behind its time the latest message went out
  std::uint64_t worst_index = 0;  // which message that was (1 = the first published)
  std::uint64_t late_over_1ms = 0;
  int loops = 0;
  std::uint64_t clock_steps = 0;  // steps of the recorder's clock in the file, replayed without
};

// What replay learns from a recording before it publishes: the file read through and checked
// (channels of teejet topics with the schemas it knows), its clock steps and the gateways whose
// status it holds. An Error says why the file cannot be replayed with these options (without
// its name); it opens no DDS entity.
struct RecordingCheck {
  mcap::Contents contents;
  recording::ClockSteps steps;
  std::set<std::string> gateways;
};
Result<RecordingCheck> check_recording(mcap::Source& file, const ReplayOptions& options);

// Reads and checks the whole file first (channels, schemas): a damaged file or a channel of an
// unknown type is an Error before anything is published. Stops early when `stop` is set.
Result<ReplayReport> replay(const ReplayOptions& options, const std::atomic<bool>& stop);

}  // namespace teejet::replay
