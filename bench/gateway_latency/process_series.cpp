#include "process_series.hpp"

#include <algorithm>

namespace teejet::bench {
namespace {

struct Span {
  std::size_t begin = 0, end = 0;  // sample indexes [begin, end)
};

void summarize(const std::vector<ProcessSample>& series, Span span, double ticks_per_second,
               std::size_t& samples, std::uint64_t& rss, std::uint64_t& fds, std::uint64_t& threads,
               double& cpu_percent) {
  samples = span.end - span.begin;
  for (std::size_t i = span.begin; i < span.end; ++i) {
    rss = std::max(rss, series[i].rss_kib);
    fds = std::max(fds, series[i].fds);
    threads = std::max(threads, series[i].threads);
  }
  const ProcessSample& first = series[span.begin];
  const ProcessSample& last = series[span.end - 1];
  const double seconds = last.at_s - first.at_s;
  if (seconds > 0) {
    cpu_percent =
        100.0 * static_cast<double>(last.cpu_ticks - first.cpu_ticks) / ticks_per_second / seconds;
  }
}

}  // namespace

SpanComparison compare_spans(const std::vector<ProcessSample>& series, double span_s,
                             double ticks_per_second) {
  SpanComparison out;
  if (series.size() < 4 || span_s <= 0) return out;
  const double end_s = series.back().at_s;
  Span first, last;
  while (first.end < series.size() && series[first.end].at_s <= span_s) ++first.end;
  last.begin = series.size();
  while (last.begin > 0 && series[last.begin - 1].at_s >= end_s - span_s) --last.begin;
  last.end = series.size();
  // Two spans of at least two samples each, not overlapping.
  if (first.end < 2 || last.end - last.begin < 2 || last.begin < first.end) return out;
  summarize(series, first, ticks_per_second, out.first_samples, out.first_rss_max,
            out.first_fds_max, out.first_threads_max, out.first_cpu_percent);
  summarize(series, last, ticks_per_second, out.last_samples, out.last_rss_max, out.last_fds_max,
            out.last_threads_max, out.last_cpu_percent);
  return out;
}

std::string not_flat(const SpanComparison& c, const FlatBudget& budget) {
  std::string grew;
  const auto note = [&](const char* what, std::uint64_t from, std::uint64_t to) {
    if (!grew.empty()) grew += ", ";
    grew += what;
    grew += ' ' + std::to_string(from) + " -> " + std::to_string(to);
  };
  if (c.first_samples == 0) return "the run is too short to compare its first and last spans";
  if (c.last_rss_max > c.first_rss_max + budget.rss_growth_kib) {
    note("rss_kib", c.first_rss_max, c.last_rss_max);
  }
  if (c.last_fds_max > c.first_fds_max) note("fds", c.first_fds_max, c.last_fds_max);
  if (c.last_threads_max > c.first_threads_max) {
    note("threads", c.first_threads_max, c.last_threads_max);
  }
  return grew;
}

std::vector<double> cpu_percent_per_interval(const std::vector<ProcessSample>& series,
                                             double ticks_per_second) {
  std::vector<double> out;
  for (std::size_t i = 1; i < series.size(); ++i) {
    const double seconds = series[i].at_s - series[i - 1].at_s;
    const double ticks = static_cast<double>(series[i].cpu_ticks - series[i - 1].cpu_ticks);
    out.push_back(seconds > 0 ? 100.0 * ticks / ticks_per_second / seconds : 0.0);
  }
  return out;
}

}  // namespace teejet::bench
