#pragma once

// What every mode of gateway_latency shares: the values of its command line, and how a mode
// ends when something it needs is refused.

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "teejet/codec/can_id.hpp"
#include "teejet/core/result.hpp"

namespace teejet::bench {

inline constexpr int kExitFailure = 1;

struct Options {
  // DDS
  int domain = 0;
  std::string profile;
  // Latency series
  std::string label = "run";
  int samples = 1000;
  int warmup = 100;
  int pace_min_ms = 10;
  int pace_max_ms = 20;
  std::string raw_dir;
  // The bench valve (gateway mode)
  std::string can = "vcan0";
  std::uint32_t serial = 900001;
  int address = codec::kLastValveAddress;
  // Under load on the host (gateway and baseline modes): an in-process gateway with this many
  // simulated valves beside the bench valve, on this poll schedule (in_process_gateway.hpp).
  int load_valves = 0;
  std::string load_config;
  // Baseline child (receive mode)
  std::string topic;
  int count = 0;
  int timeout_s = 120;
  // Resources mode
  std::vector<int> pids;
  double window_s = 30.0;
  double settle_s = 5.0;
  std::string interface;
  bool subscribe = false;
  // Target Degrees to valves 1..moved_valves in turn, in the window.
  double commands_per_second = 0;
  std::uint32_t moved_valves = 32;
  double rss_every_s = 0;  // sample RSS, fds, threads, CPU this often in the window (the soak)
  double compare_s = 0;    // compare the first and the last this many seconds of the samples
  double drain_s = 10;     // after the window, wait this long at most for the last statuses
  bool check = false;      // exit 1 when a command has no final state or the footprint grew
};

// Reports what was refused on stderr; returns the exit status for the mode to return.
inline int fail(const Error& error) {
  std::fprintf(stderr, "gateway_latency: %s\n", error.reason.c_str());
  return kExitFailure;
}

}  // namespace teejet::bench
