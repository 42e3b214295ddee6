#include "series.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <thread>

namespace teejet::bench {

namespace {

double percentile_us(const std::vector<std::int64_t>& sorted, double percent) {
  // Nearest rank: the p99 of 1000 samples is the 990th smallest.
  const auto rank =
      static_cast<std::size_t>(std::ceil(percent / 100.0 * static_cast<double>(sorted.size())));
  return static_cast<double>(sorted[std::max<std::size_t>(rank, 1) - 1]) / 1000.0;
}

}  // namespace

std::int64_t realtime_ns() {
  timespec now{};
  clock_gettime(CLOCK_REALTIME, &now);
  return std::int64_t{now.tv_sec} * 1'000'000'000 + now.tv_nsec;
}

void report(const Series& series, const Options& options) {
  std::vector<std::int64_t> sorted = series.latencies_ns;
  std::sort(sorted.begin(), sorted.end());
  std::printf("RESULT label=%s metric=%s n=%zu lost=%zu", options.label.c_str(),
              series.metric.c_str(), sorted.size(), series.lost);
  if (!sorted.empty()) {
    std::printf(" min_us=%.1f p50_us=%.1f p90_us=%.1f p99_us=%.1f max_us=%.1f",
                static_cast<double>(sorted.front()) / 1000.0, percentile_us(sorted, 50),
                percentile_us(sorted, 90), percentile_us(sorted, 99),
                static_cast<double>(sorted.back()) / 1000.0);
  }
  std::printf("\n");
  std::fflush(stdout);
  if (!options.raw_dir.empty()) {
    std::string path = options.raw_dir;
    path.append("/").append(options.label).append("-").append(series.metric).append(".ns");
    std::ofstream raw(path);
    for (const auto latency : series.latencies_ns) raw << latency << '\n';
  }
}

Pacer::Pacer(const Options& options)
    : gap_us_(options.pace_min_ms * 1000, options.pace_max_ms * 1000) {}

void Pacer::wait() { std::this_thread::sleep_for(std::chrono::microseconds(gap_us_(random_))); }

}  // namespace teejet::bench
