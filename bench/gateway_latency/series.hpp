#pragma once

// Latency series: the clock both ends read, the series and its report line, and the pacing
// between samples.
//
// One kernel, one CLOCK_REALTIME for both ends: one-way latencies are differences of two
// readings of the same clock.

#include <cstddef>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "options.hpp"

namespace teejet::bench {

// CLOCK_REALTIME in nanoseconds: the clock of the kernel's CAN receive stamps and of the
// gateway's *_ns fields, so that readings taken here subtract from theirs.
std::int64_t realtime_ns();

struct Series {
  std::string metric;
  std::vector<std::int64_t> latencies_ns;
  std::size_t lost = 0;
};

// Prints `RESULT label=... metric=... n=... lost=... min_us=... p50_us=... p90_us=... p99_us=...
// max_us=...` (the percentiles only when a sample arrived) and, with --raw-dir, writes every
// latency to <raw-dir>/<label>-<metric>.ns.
void report(const Series& series, const Options& options);

// Random gaps between samples, so that the measurement never phase-locks with the gateway's own
// periodic work (its 50 ms clock thread, the 1 s status, I'm Here).
class Pacer {
 public:
  explicit Pacer(const Options& options);
  void wait();

 private:
  std::mt19937 random_{20240404};  // fixed: every run paces the same way
  std::uniform_int_distribution<int> gap_us_;
};

}  // namespace teejet::bench
