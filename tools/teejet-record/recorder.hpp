#pragma once

// teejet-record's recording: DDS readers for the chosen teejet topics, and the MCAP file(s) their
// samples go to. One thread (the caller's) takes samples and writes; nothing runs on Fast DDS's
// threads but the wake-up of a wait.

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "teejet/core/result.hpp"
#include "teejet/core/time.hpp"

namespace teejet::record {

struct RecorderOptions {
  std::string output;               // "run.mcap"; with max_size: run_000.mcap, run_001.mcap, ...
  std::vector<std::string> topics;  // globs; empty: every teejet topic
  std::optional<Duration> duration;
  std::uint64_t max_size = 0;  // bytes per file before the next one starts; 0: one file
  std::string compression = "zstd";
  std::size_t chunk_size = 1 << 20;
  // How often the open chunk is closed and handed to the system: what a crash can lose.
  Duration flush_period = std::chrono::seconds(1);
  std::string candump_path;  // also write teejet/can/frame as candump -L text
  int domain = 0;
  std::string profile_file;
};

struct TopicTally {
  std::uint64_t messages = 0;
  std::uint64_t bytes = 0;  // payload bytes
};

struct Progress {
  Duration elapsed{};
  std::uint64_t messages = 0;
  std::uint64_t file_bytes = 0;  // all files so far
  std::vector<std::string> files;
  std::map<std::string, TopicTally> topics;       // by channel topic (incl. "/disposed" ones)
  std::uint64_t unknown_disposals = 0;            // of instances never seen alive: not recordable
  std::uint64_t frames_without_candump_line = 0;  // in the MCAP file, not in --candump
  // Times the recorder joined the domain again over TCP, having met no gateway (docs/recording.md)
  std::uint64_t rejoins = 0;
};

// The topics `globs` select, in catalog order; an Error names a glob that selects none.
Result<std::vector<std::string>> select_topics(const std::vector<std::string>& globs);

// The n-th file of a split recording: "run.mcap" -> "run_000.mcap", n = 0, 1, ...
std::string split_file_name(const std::string& output, int index);

// Records until `stop` is set (a signal), the duration passes, or a write fails. `report` is
// called about once a second and at the end. The file is always finished (summary, footer) when
// this returns, also after an error.
// ErrorCode::kStalled: the participant's Fast DDS event thread stopped (docs/topics.md, "A
// participant that stops"); the participant is left undeleted and the caller must end the
// process without running destructors (std::_Exit).
Result<Progress> record(const RecorderOptions& options, const std::atomic<bool>& stop,
                        const std::function<void(const Progress&)>& report,
                        const std::function<void()>& on_started = {});

}  // namespace teejet::record
