// The soak's verdicts: a command left without a final state, or a footprint that grew between
// the first and the last span of a run, must fail it; warm-up inside the first span must not.
#include <gtest/gtest.h>

#include "command_ledger.hpp"
#include "process_series.hpp"

namespace teejet::bench {
namespace {

CommandStatus status_of(std::uint32_t id, CommandState state, const std::string& reason = "") {
  CommandStatus status;
  status.command_id(id);
  status.state(state);
  status.reason(reason);
  return status;
}

TEST(CommandLedger, EveryCommandNeedsExactlyOneFinalState) {
  CommandLedger ledger;
  for (int i = 0; i < 5; ++i) ledger.next_id();
  ledger.record(status_of(1, COMMAND_ACCEPTED));
  ledger.record(status_of(1, COMMAND_COMPLETED));
  ledger.record(status_of(2, COMMAND_ACCEPTED));
  ledger.record(status_of(2, COMMAND_SUPERSEDED));
  ledger.record(status_of(3, COMMAND_REJECTED, "valve TJV000012 is offline"));
  ledger.record(status_of(4, COMMAND_ACCEPTED));
  ledger.record(status_of(4, COMMAND_TIMED_OUT, "valve TJV000007 went offline"));
  ledger.record(status_of(4, COMMAND_COMPLETED));  // a second final state: a bug in the gateway
  ledger.record(status_of(9, COMMAND_COMPLETED));  // never sent
  const LedgerCounts counts = ledger.counts();
  EXPECT_EQ(counts.sent, 5u);
  EXPECT_EQ(counts.accepted, 3u);
  EXPECT_EQ(counts.completed, 1u);
  EXPECT_EQ(counts.superseded, 1u);
  EXPECT_EQ(counts.rejected, 1u);
  EXPECT_EQ(counts.timed_out, 1u);
  EXPECT_EQ(counts.unaccounted, 1u);  // command 5
  EXPECT_EQ(counts.duplicate_finals, 1u);
  EXPECT_EQ(counts.unknown, 1u);
  EXPECT_EQ(counts.reasons.at("valve TJV* is offline"), 1u);
  EXPECT_EQ(counts.reasons.at("valve TJV* went offline"), 1u);
}

TEST(CommandLedger, ReasonsAreGroupedWithTheirNumbersMasked) {
  EXPECT_EQ(mask_numbers("address 0xD9 is claimed by TJV000002 and TJV000003"),
            "address 0x* is claimed by TJV* and TJV*");
  EXPECT_EQ(mask_numbers("position 29.4 did not reach 80.0 in time."),
            "position * did not reach * in time.");
  EXPECT_EQ(mask_numbers("no numbers"), "no numbers");
}

// Ten samples a second apart: RSS, fds, threads, CPU ticks (100 a second).
std::vector<ProcessSample> run(std::vector<std::uint64_t> rss, std::vector<std::uint64_t> fds,
                               std::uint64_t ticks_per_sample) {
  std::vector<ProcessSample> series;
  for (std::size_t i = 0; i < rss.size(); ++i) {
    series.push_back({static_cast<double>(i), rss[i], fds[i], 9, i * ticks_per_sample});
  }
  return series;
}

TEST(ProcessSeries, WarmUpInTheFirstSpanIsFlat) {
  const auto series = run({19000, 19500, 20000, 20400, 20400, 20400, 20400, 20400, 20400, 20400},
                          {12, 12, 12, 12, 12, 12, 12, 12, 12, 12}, 5);
  const SpanComparison comparison = compare_spans(series, 3.0, 100.0);
  EXPECT_EQ(comparison.first_samples, 4u);  // 0..3 s
  EXPECT_EQ(comparison.last_samples, 4u);   // 6..9 s
  EXPECT_EQ(comparison.first_rss_max, 20400u);
  EXPECT_DOUBLE_EQ(comparison.last_cpu_percent, 5.0);
  EXPECT_EQ(not_flat(comparison, FlatBudget{}), "");
}

TEST(ProcessSeries, GrowthAtTheEndIsNotFlat) {
  const auto series = run({20000, 20000, 20000, 20000, 20500, 21000, 21500, 22000, 22500, 23000},
                          {12, 12, 12, 12, 12, 13, 13, 14, 14, 15}, 5);
  const SpanComparison comparison = compare_spans(series, 3.0, 100.0);
  EXPECT_EQ(not_flat(comparison, FlatBudget{}), "rss_kib 20000 -> 23000, fds 12 -> 15");
}

TEST(ProcessSeries, ARunShorterThanTwoSpansCannotBeCalledFlat) {
  const auto series = run({1, 1, 1, 1}, {1, 1, 1, 1}, 0);
  EXPECT_EQ(compare_spans(series, 3.0, 100.0).first_samples, 0u);
  EXPECT_NE(not_flat(compare_spans(series, 3.0, 100.0), FlatBudget{}), "");
}

TEST(ProcessSeries, CpuPerIntervalIsPercentOfOneCore) {
  const auto series = run({1, 1, 1}, {1, 1, 1}, 25);
  EXPECT_EQ(cpu_percent_per_interval(series, 100.0), (std::vector<double>{25.0, 25.0}));
}

}  // namespace
}  // namespace teejet::bench
