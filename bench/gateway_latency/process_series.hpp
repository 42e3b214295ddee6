#pragma once

// A process's footprint over a long run, sampled at a fixed period, and the soak's question
// about it: is the end of the run the same as its beginning? Pure; the sampling is in
// process_stats.

#include <cstdint>
#include <string>
#include <vector>

namespace teejet::bench {

struct ProcessSample {
  double at_s = 0;              // since the window began
  std::uint64_t rss_kib = 0;    // VmRSS
  std::uint64_t fds = 0;        // entries of /proc/PID/fd
  std::uint64_t threads = 0;    // Threads: of /proc/PID/status
  std::uint64_t cpu_ticks = 0;  // utime + stime so far
};

// The first and the last `span_s` of a series side by side.
struct SpanComparison {
  std::size_t first_samples = 0, last_samples = 0;
  std::uint64_t first_rss_max = 0, last_rss_max = 0;
  std::uint64_t first_fds_max = 0, last_fds_max = 0;
  std::uint64_t first_threads_max = 0, last_threads_max = 0;
  double first_cpu_percent = 0, last_cpu_percent = 0;  // mean over each span
};

// nullopt-like: first_samples == 0 when the series does not cover two spans of two samples.
SpanComparison compare_spans(const std::vector<ProcessSample>& series, double span_s,
                             double ticks_per_second);

// Budgets of a flat run: RSS may end at most `rss_growth_kib` above the first span's highest
// value; file descriptors and threads may not end above the first span's highest value.
struct FlatBudget {
  std::uint64_t rss_growth_kib = 1024;
};

// Empty when flat; otherwise what grew, e.g. "fds 31 -> 35".
std::string not_flat(const SpanComparison& comparison, const FlatBudget& budget);

// CPU percent of one core between consecutive samples: one value fewer than samples.
std::vector<double> cpu_percent_per_interval(const std::vector<ProcessSample>& series,
                                             double ticks_per_second);

}  // namespace teejet::bench
