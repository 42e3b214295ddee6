// resources mode: CPU and memory of running processes over a window, the bus frame rate, and
// (--subscribe) what an ECU reading every gateway topic receives meanwhile.

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <thread>
#include <vector>

#include "command_ledger.hpp"
#include "dds_support.hpp"
#include "listeners.hpp"
#include "modes.hpp"
#include "process_series.hpp"
#include "process_stats.hpp"

namespace teejet::bench {

namespace {

namespace topics = dds::topics;

// The gateway's own counters, from one GatewayStatus sample.
struct GatewayCounters {
  std::string gateway;
  std::uint64_t frames_in = 0;
  std::uint64_t frames_out = 0;
  std::uint64_t stamp_ns = 0;
};

// An ECU reading every topic the gateway writes, so the gateway's writers deliver (with no
// reader matched, a write ends inside the gateway) and the window measures a working gateway.
class EcuReadingEverything {
 public:
  static Result<std::unique_ptr<EcuReadingEverything>> create(const Options& options) {
    auto participant = dds::Participant::create(
        {.domain = options.domain, .profile_file = options.profile, .name = "gateway-latency-ecu"});
    if (!participant) return participant.error();
    std::unique_ptr<EcuReadingEverything> ecu(new EcuReadingEverything(std::move(*participant)));
    if (Status read = ecu->read_every_topic(); !read) return read.error();
    return ecu;
  }

  std::uint64_t samples() const { return samples_; }

  // Distinct serials on the presence topic: how many valves this ECU can see at all.
  std::size_t valves_seen() const {
    std::lock_guard lock(mutex_);
    return serials_seen_.size();
  }

  std::optional<GatewayCounters> gateway_counters() const {
    std::lock_guard lock(mutex_);
    return gateway_counters_;
  }

  // A mark, and the first status heard after it from `gateway` (any gateway when empty): a
  // window's rates come from two statuses one gateway wrote inside it, however late a loaded
  // host delivers them (the last status before the window may be older than the window's own
  // conditions, and with several gateways another gateway's).
  std::size_t mark_gateway_status(std::string gateway = {}) {
    std::lock_guard lock(mutex_);
    first_status_after_.push_back({std::move(gateway), std::nullopt});
    return first_status_after_.size() - 1;
  }
  std::optional<GatewayCounters> first_gateway_status_after(std::size_t mark) const {
    std::lock_guard lock(mutex_);
    return first_status_after_.at(mark).first;
  }

  // Commands as a commanding ECU writes them, with the statuses they got.
  Status open_commands() {
    auto writer = open_writer<ValveCommand>(*participant_, topics::command_writer_qos());
    if (!writer) return writer.error();
    command_writer_ = *writer;
    auto reader =
        open_reader<CommandStatus>(*participant_, topics::status_reader_qos(), &statuses_);
    if (!reader) return reader.error();
    status_reader_ = *reader;
    return {};
  }
  bool commands_matched() const {
    return command_writer_ && status_reader_ && matched(command_writer_) && matched(status_reader_);
  }
  void move(std::uint32_t serial, float degrees) {
    ValveCommand command;
    command.serial(serial);
    command.command_id(ledger_.next_id());
    command.origin(kOrigin);
    command.kind(COMMAND_TARGET_DEGREES);
    command.degrees(degrees);
    command.speed_percent(100);
    command_writer_->write(&command);
  }
  const CommandLedger& ledger() const { return ledger_; }

 private:
  explicit EcuReadingEverything(std::unique_ptr<dds::Participant> participant)
      : participant_(std::move(participant)) {}

  // Readers for presence, every telemetry topic and the gateway status; the first refusal ends
  // it.
  Status read_every_topic() {
    auto presence =
        open_reader<ValvePresence>(*participant_, topics::state_reader_qos(), &presence_);
    if (!presence) return presence.error();
    if (Status counted = count_each(std::type_identity<dds::TelemetrySample>{}); !counted) {
      return counted;
    }
    auto status =
        open_reader<GatewayStatus>(*participant_, topics::state_reader_qos(), &gateway_status_);
    if (!status) return status.error();
    return {};
  }

  // A counting reader per sample type, in order; && stops at the first refusal.
  template <class... Samples>
  Status count_each(std::type_identity<std::variant<Samples...>>) {
    Status counted;
    (void)((counted = count<Samples>()).ok() && ...);
    return counted;
  }

  // A reader that only counts the samples of its topic.
  template <class Sample>
  Status count() {
    auto counter = std::make_unique<OnSample<Sample>>([this](const Sample&) { ++samples_; });
    auto reader = open_reader<Sample>(*participant_, topics::state_reader_qos(), counter.get());
    counters_.push_back(std::move(counter));
    if (!reader) return reader.error();
    return {};
  }

  static constexpr const char* kOrigin = "gateway-latency-soak";
  std::atomic<std::uint64_t> samples_{0};
  mutable std::mutex mutex_;
  fdds::DataWriter* command_writer_ = nullptr;
  fdds::DataReader* status_reader_ = nullptr;
  CommandLedger ledger_;
  OnSample<CommandStatus> statuses_{[this](const CommandStatus& status) {
    if (status.origin().to_string() == kOrigin) ledger_.record(status);
  }};
  std::optional<GatewayCounters> gateway_counters_;
  struct StatusAfterMark {
    std::string from;  // empty: any gateway
    std::optional<GatewayCounters> first;
  };
  std::vector<StatusAfterMark> first_status_after_;
  std::set<std::uint32_t> serials_seen_;
  OnSample<ValvePresence> presence_{[this](const ValvePresence& sample) {
    ++samples_;
    std::lock_guard lock(mutex_);
    serials_seen_.insert(sample.serial());
  }};
  OnSample<GatewayStatus> gateway_status_{[this](const GatewayStatus& status) {
    std::lock_guard lock(mutex_);
    gateway_counters_ = GatewayCounters{status.gateway().to_string(), status.frames_in(),
                                        status.frames_out(), status.stamp_ns()};
    for (auto& mark : first_status_after_) {
      if (!mark.first && (mark.from.empty() || mark.from == gateway_counters_->gateway)) {
        mark.first = gateway_counters_;
      }
    }
  }};
  std::vector<std::unique_ptr<fdds::DataReaderListener>> counters_;
  std::unique_ptr<dds::Participant> participant_;  // last: destroyed first, before the listeners
};

void print_series(const Options& options, const std::string& process,
                  const std::vector<ProcessSample>& series, double ticks_per_second) {
  const auto [lowest, highest] = std::minmax_element(
      series.begin(), series.end(),
      [](const ProcessSample& a, const ProcessSample& b) { return a.rss_kib < b.rss_kib; });
  std::printf(
      "RSS label=%s process=%s samples=%zu every_s=%.1f first_kib=%llu lowest_kib=%llu "
      "highest_kib=%llu last_kib=%llu spread_kib=%llu\n",
      options.label.c_str(), process.c_str(), series.size(), options.rss_every_s,
      static_cast<unsigned long long>(series.front().rss_kib),
      static_cast<unsigned long long>(lowest->rss_kib),
      static_cast<unsigned long long>(highest->rss_kib),
      static_cast<unsigned long long>(series.back().rss_kib),
      static_cast<unsigned long long>(highest->rss_kib - lowest->rss_kib));
  // The curves, to tell a first-minutes rise that levels off from a steady leak.
  const auto join = [&](auto value) {
    std::string text;
    for (const ProcessSample& sample : series) {
      if (!text.empty()) text += ',';
      text += std::to_string(value(sample));
    }
    return text;
  };
  const char* label = options.label.c_str();
  std::printf("RSS_SERIES label=%s process=%s every_s=%.1f kib=%s\n", label, process.c_str(),
              options.rss_every_s, join([](const ProcessSample& s) { return s.rss_kib; }).c_str());
  std::printf("FD_SERIES label=%s process=%s every_s=%.1f fds=%s\n", label, process.c_str(),
              options.rss_every_s, join([](const ProcessSample& s) { return s.fds; }).c_str());
  std::printf("THREAD_SERIES label=%s process=%s every_s=%.1f threads=%s\n", label, process.c_str(),
              options.rss_every_s, join([](const ProcessSample& s) { return s.threads; }).c_str());
  std::string cpu;
  for (const double percent : cpu_percent_per_interval(series, ticks_per_second)) {
    if (!cpu.empty()) cpu += ',';
    char value[32];
    std::snprintf(value, sizeof value, "%.1f", percent);
    cpu += value;
  }
  std::printf("CPU_SERIES label=%s process=%s every_s=%.1f percent=%s\n", label, process.c_str(),
              options.rss_every_s, cpu.c_str());
}

void print_comparison(const Options& options, const std::string& process, const SpanComparison& c,
                      const std::string& grew) {
  std::printf(
      "COMPARE label=%s process=%s span_s=%.0f samples=%zu/%zu rss_max_kib=%llu/%llu "
      "fds_max=%llu/%llu threads_max=%llu/%llu cpu_percent=%.2f/%.2f flat=%s%s%s\n",
      options.label.c_str(), process.c_str(), options.compare_s, c.first_samples, c.last_samples,
      static_cast<unsigned long long>(c.first_rss_max),
      static_cast<unsigned long long>(c.last_rss_max),
      static_cast<unsigned long long>(c.first_fds_max),
      static_cast<unsigned long long>(c.last_fds_max),
      static_cast<unsigned long long>(c.first_threads_max),
      static_cast<unsigned long long>(c.last_threads_max), c.first_cpu_percent, c.last_cpu_percent,
      grew.empty() ? "yes" : "no", grew.empty() ? "" : " grew=", grew.c_str());
}

void print_commands(const Options& options, const LedgerCounts& counts) {
  std::printf(
      "COMMANDS label=%s sent=%u accepted=%u completed=%u superseded=%u timed_out=%u "
      "rejected=%u unaccounted=%u duplicate_finals=%u unknown=%u\n",
      options.label.c_str(), counts.sent, counts.accepted, counts.completed, counts.superseded,
      counts.timed_out, counts.rejected, counts.unaccounted, counts.duplicate_finals,
      counts.unknown);
  for (const auto& [reason, count] : counts.reasons) {
    std::printf("REASON label=%s count=%u reason=\"%s\"\n", options.label.c_str(), count,
                reason.c_str());
  }
}

}  // namespace

int run_resources(const Options& options) {
  std::unique_ptr<EcuReadingEverything> ecu;
  if (options.subscribe) {
    auto created = EcuReadingEverything::create(options);
    if (!created) return fail(created.error());
    ecu = std::move(*created);
    if (options.commands_per_second > 0) {
      if (Status opened = ecu->open_commands(); !opened) return fail(opened.error());
      if (!wait_until([&] { return ecu->commands_matched(); }, kDiscoveryTimeout)) {
        std::fprintf(stderr, "gateway_latency: no gateway took commands on domain %d\n",
                     options.domain);
        return kExitFailure;
      }
    }
  } else if (options.commands_per_second > 0) {
    std::fprintf(stderr, "gateway_latency: --commands-per-second needs --subscribe\n");
    return 2;
  }
  // Discovery, the late-joiner burst and the gateway's start-up are not part of the window.
  const auto settled = std::chrono::steady_clock::now() +
                       std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                           std::chrono::duration<double>(options.settle_s));
  // The ECU's figures mean something only once it hears the gateway: wait for that rather than
  // hope the settling time covers discovery.
  if (ecu && !wait_until([&] { return ecu->gateway_counters().has_value(); }, kDiscoveryTimeout)) {
    std::fprintf(stderr, "gateway_latency: no gateway status on domain %d after %lld s\n",
                 options.domain, static_cast<long long>(kDiscoveryTimeout.count()));
    return kExitFailure;
  }
  std::this_thread::sleep_until(settled);

  struct Start {
    int pid;
    std::uint64_t ticks;
  };
  std::vector<Start> starts;
  for (const int pid : options.pids) {
    const auto ticks = cpu_ticks(pid);
    if (!ticks) {
      std::fprintf(stderr, "gateway_latency: no process %d\n", pid);
      return kExitFailure;
    }
    starts.push_back({pid, *ticks});
  }
  std::optional<std::uint64_t> frames_before;
  if (!options.interface.empty()) frames_before = bus_frames(options.interface);
  const auto samples_before = ecu ? ecu->samples() : 0;
  const std::size_t window_start_mark = ecu ? ecu->mark_gateway_status() : 0;
  const auto window_start = std::chrono::steady_clock::now();

  // The window is a measurement period, not a wait for anything; meanwhile commands go out at
  // their rate and RSS is sampled at its period.
  const auto window_end = window_start + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                             std::chrono::duration<double>(options.window_s));
  const auto period = [](double seconds) {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
        std::chrono::duration<double>(seconds));
  };
  auto next_command = window_start;
  auto next_sample = window_start;
  std::vector<std::vector<ProcessSample>> series(options.pids.size());
  std::uint32_t moves = 0;
  for (;;) {
    const auto now = std::chrono::steady_clock::now();
    if (options.rss_every_s > 0 && now >= next_sample) {
      const double at_s = std::chrono::duration<double>(now - window_start).count();
      for (std::size_t i = 0; i < options.pids.size(); ++i) {
        const int pid = options.pids[i];
        series[i].push_back({at_s, status_value(pid, "VmRSS"), open_fds(pid), thread_count(pid),
                             cpu_ticks(pid).value_or(0)});
      }
      next_sample += period(options.rss_every_s);
    }
    if (options.commands_per_second > 0 && now >= next_command) {
      // Valves in turn, each to the other end of a 10-80 degree stroke every other time.
      const std::uint32_t valves = options.moved_valves;
      ecu->move(1 + moves % valves, (moves / valves) % 2 ? 10.0F : 80.0F);
      ++moves;
      next_command += period(1.0 / options.commands_per_second);
    }
    if (now >= window_end) break;
    auto wake = window_end;
    if (options.rss_every_s > 0) wake = std::min(wake, next_sample);
    if (options.commands_per_second > 0) wake = std::min(wake, next_command);
    std::this_thread::sleep_until(wake);
  }

  const double window =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - window_start).count();
  // The end mark is set as the window closes when the gateway was heard inside it, else once
  // it is heard (below): then the span runs past the window, under the same conditions.
  std::optional<GatewayCounters> gateway_before;
  std::optional<std::size_t> window_end_mark;
  if (ecu) {
    gateway_before = ecu->first_gateway_status_after(window_start_mark);
    if (gateway_before) window_end_mark = ecu->mark_gateway_status(gateway_before->gateway);
  }
  const auto samples_after = ecu ? ecu->samples() : 0;
  const double ticks_per_second = static_cast<double>(::sysconf(_SC_CLK_TCK));
  for (const auto& start : starts) {
    const auto ticks = cpu_ticks(start.pid);
    if (!ticks) {
      std::fprintf(stderr, "gateway_latency: process %d ended during the window\n", start.pid);
      return kExitFailure;
    }
    const double cpu_seconds = static_cast<double>(*ticks - start.ticks) / ticks_per_second;
    std::printf(
        "RESOURCES label=%s process=%s window_s=%.1f cpu_percent=%.2f rss_kib=%llu "
        "hwm_kib=%llu\n",
        options.label.c_str(), process_name(start.pid).c_str(), window,
        100.0 * cpu_seconds / window,
        static_cast<unsigned long long>(status_value(start.pid, "VmRSS")),
        static_cast<unsigned long long>(status_value(start.pid, "VmHWM")));
  }
  bool failed = false;
  for (std::size_t i = 0; i < series.size(); ++i) {
    if (series[i].empty()) continue;
    const std::string name = process_name(options.pids[i]);
    print_series(options, name, series[i], ticks_per_second);
    if (options.compare_s > 0) {
      const SpanComparison comparison =
          compare_spans(series[i], options.compare_s, ticks_per_second);
      const std::string grew = not_flat(comparison, FlatBudget{});
      print_comparison(options, name, comparison, grew);
      failed = failed || !grew.empty();
    }
  }
  if (ecu && options.commands_per_second > 0) {
    // The last commands need their time to finish: wait for every final state, with a deadline.
    wait_until([&] { return ecu->ledger().unaccounted() == 0; },
               std::chrono::milliseconds(static_cast<long long>(options.drain_s * 1000)));
    const LedgerCounts counts = ecu->ledger().counts();
    print_commands(options, counts);
    failed = failed || counts.unaccounted > 0 || counts.duplicate_finals > 0 || counts.unknown > 0;
  }
  if (frames_before) {
    const auto frames_after = bus_frames(options.interface);
    std::printf("BUS label=%s interface=%s frames_per_s=%.1f\n", options.label.c_str(),
                options.interface.c_str(),
                static_cast<double>(frames_after.value_or(0) - *frames_before) / window);
  }
  if (ecu) {
    std::printf("SUBSCRIBER label=%s samples_per_s=%.1f valves_seen=%zu", options.label.c_str(),
                static_cast<double>(samples_after - samples_before) / window, ecu->valves_seen());
    // The gateway writes its status every second: the first one after the end mark closes the
    // span its counters are compared over.
    const auto heard = [&](std::size_t mark) {
      return wait_until([&] { return ecu->first_gateway_status_after(mark).has_value(); },
                        kDiscoveryTimeout);
    };
    if (!window_end_mark && heard(window_start_mark)) {
      gateway_before = ecu->first_gateway_status_after(window_start_mark);
      window_end_mark = ecu->mark_gateway_status(gateway_before->gateway);
    }
    if (!window_end_mark || !heard(*window_end_mark)) {
      std::fprintf(stderr,
                   "gateway_latency: %s: no two gateway statuses within %lld s of the window\n",
                   options.label.c_str(), static_cast<long long>(kDiscoveryTimeout.count()));
    }
    const auto gateway_after =
        window_end_mark ? ecu->first_gateway_status_after(*window_end_mark) : std::nullopt;
    if (gateway_before && gateway_after && gateway_after->gateway == gateway_before->gateway &&
        gateway_after->stamp_ns > gateway_before->stamp_ns) {
      const double seconds =
          static_cast<double>(gateway_after->stamp_ns - gateway_before->stamp_ns) / 1e9;
      std::printf(
          " gateway_frames_in_per_s=%.1f gateway_frames_out_per_s=%.1f",
          static_cast<double>(gateway_after->frames_in - gateway_before->frames_in) / seconds,
          static_cast<double>(gateway_after->frames_out - gateway_before->frames_out) / seconds);
    }
    std::printf("\n");
  }
  std::fflush(stdout);
  return options.check && failed ? kExitFailure : 0;
}

}  // namespace teejet::bench
