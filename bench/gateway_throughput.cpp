// gateway_throughput: how many frames a second the gateway takes from the bus into DDS without
// losing one, and what each frame costs its bus reader thread, beside bare Fast DDS writing the
// same samples and the physical limit of a 500 kbit/s bus (docs/performance.md, "Throughput").
//
// In-process: a real gateway::Gateway (bridge, DDS writers, its reader thread) on a virtual
// bus, and a flood endpoint on the same bus that announces 32 valves (I'm Here) and then sends
// Position frames round-robin, paced in 1 ms bursts, at each rate asked for. A rate passes when
// every frame sent was taken off the bus (none dropped by the bounded receive queue) and
// attributed to its valve. Creates a DDS participant: run it inside tests/netns/isolated.

#include <spdlog/spdlog.h>
#include <time.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "gateway.hpp"
#include "teejet/can/virtual_bus.hpp"
#include "teejet/codec/can_id.hpp"
#include "teejet/codec/codec.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/valvePubSubTypes.h"

namespace {

using namespace teejet;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

constexpr int kValves = 32;
// A 500 kbit/s bus: an extended frame with 8 data bytes is 128 bits before stuffing, up to 153
// with worst-case stuffing, plus 3 bits of interframe space: 3,200 to 3,800 frames a second.
constexpr double kFullBusFramesPerSecond = 500'000.0 / 131.0;

struct Options {
  std::vector<double> rates{4'000, 20'000, 80'000, 160'000, 320'000};
  double seconds = 2.0;
  int domain = 0;
  std::string profile;
};

// Any thread's CPU clock by its id, as glibc's pthread_getcpuclockid builds it (Linux ABI).
double thread_cpu_seconds(pid_t tid) {
  const clockid_t clock = static_cast<clockid_t>((~static_cast<unsigned>(tid) << 3) | 6u);
  timespec used{};
  if (::clock_gettime(clock, &used) != 0) return 0;
  return static_cast<double>(used.tv_sec) + static_cast<double>(used.tv_nsec) / 1e9;
}

// The gateway's bus reader, by the name Gateway::start gives it.
std::optional<pid_t> reader_thread() {
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::ifstream comm(task.path() / "comm");
    std::string name;
    std::getline(comm, name);
    if (name == "tj-bus-reader") return static_cast<pid_t>(std::stoi(task.path().filename()));
  }
  return std::nullopt;
}

double this_thread_cpu_seconds() {
  timespec now{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + static_cast<double>(now.tv_nsec) / 1e9;
}

codec::CanFrame frame_of(std::uint8_t address, const codec::FromValveMessage& message) {
  return *codec::encode(address, message);
}

std::uint8_t address_of(int valve) {
  return static_cast<std::uint8_t>(codec::kFirstValveAddress + valve);
}

struct RateResult {
  double rate = 0;
  std::uint64_t sent = 0;
  std::uint64_t taken = 0;
  std::uint64_t dropped = 0;
  std::uint64_t unattributed = 0;
  double reader_cpu_s = 0;
  double seconds = 0;
  bool passed() const { return dropped == 0 && unattributed == 0 && taken == sent; }
};

std::optional<RateResult> run_rate(const Options& options, double rate, int round) {
  const std::string bus_name =
      "throughput-" + std::to_string(::getpid()) + "-" + std::to_string(round);
  gateway::GatewayConfig config;
  config.can = "virtual:" + bus_name;
  config.domain = options.domain;
  config.profile_file = options.profile;
  config.stop_valves_on_exit = false;
  config.bridge.gateway_name = "throughput-bench";
  config.bridge.offline_after = 3600s;  // the flood announces the valves once
  auto backend = gateway::make_bus_backend(config);
  if (!backend) {
    std::fprintf(stderr, "gateway_throughput: %s\n", backend.error().reason.c_str());
    return std::nullopt;
  }
  can::Bus* gateway_bus = backend->bus.get();
  gateway::Gateway gateway(config, std::move(*backend));
  if (auto started = gateway.start(); !started) {
    std::fprintf(stderr, "gateway_throughput: %s\n", started.error().reason.c_str());
    return std::nullopt;
  }
  // The gateway's poll requests land here and are never read: a small queue, dropped.
  can::VirtualBus flood(bus_name, {.filters = can::valve_side_filters(), .queue_limit = 16});
  if (auto opened = flood.open(); !opened) {
    std::fprintf(stderr, "gateway_throughput: %s\n", opened.error().reason.c_str());
    return std::nullopt;
  }

  std::vector<codec::CanFrame> announce;
  for (int valve = 0; valve < kValves; ++valve) {
    announce.push_back(frame_of(
        address_of(valve),
        codec::IAmHere{.part_number = 1, .serial = 100000u + static_cast<std::uint32_t>(valve)}));
  }
  (void)flood.send_batch(announce);
  const auto announced = Clock::now() + 5s;
  while (gateway.bridge().valves().size() < kValves && Clock::now() < announced) {
    std::this_thread::sleep_for(1ms);
  }
  if (gateway.bridge().valves().size() < kValves) {
    std::fprintf(stderr, "gateway_throughput: the gateway knows %zu of %d valves after 5 s\n",
                 gateway.bridge().valves().size(), kValves);
    return std::nullopt;
  }
  const auto reader = reader_thread();
  if (!reader) {
    std::fprintf(stderr, "gateway_throughput: no thread named tj-bus-reader\n");
    return std::nullopt;
  }

  const auto before = gateway_bus->statistics();
  const auto counters_before = gateway.bridge().counters();
  RateResult result;
  result.rate = rate;
  const double reader_cpu0 = thread_cpu_seconds(*reader);
  const auto start = Clock::now();
  const auto end = start + std::chrono::duration_cast<Clock::duration>(
                               std::chrono::duration<double>(options.seconds));
  std::vector<codec::CanFrame> burst;
  std::uint64_t sequence = 0;
  auto next = start;
  while (next < end) {
    // Frames due by the end of this millisecond.
    const double due_by = rate * std::chrono::duration<double>(next + 1ms - start).count();
    burst.clear();
    while (static_cast<double>(result.sent + burst.size()) < due_by) {
      const int valve = static_cast<int>(sequence % kValves);
      const double degrees = static_cast<double>((sequence / kValves) % 900) / 10.0;
      burst.push_back(frame_of(address_of(valve), codec::Position{degrees}));
      ++sequence;
    }
    result.sent += flood.send_batch(burst).sent;
    next += 1ms;
    std::this_thread::sleep_until(next);
  }
  // Drained: everything sent was taken or dropped.
  const auto drained = Clock::now() + 10s;
  auto now_stats = gateway_bus->statistics();
  while (now_stats.frames_in - before.frames_in + now_stats.rx_dropped - before.rx_dropped <
             result.sent &&
         Clock::now() < drained) {
    std::this_thread::sleep_for(1ms);
    now_stats = gateway_bus->statistics();
  }
  result.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  result.reader_cpu_s = thread_cpu_seconds(*reader) - reader_cpu0;
  result.taken = now_stats.frames_in - before.frames_in;
  result.dropped = now_stats.rx_dropped - before.rx_dropped;
  result.unattributed = gateway.bridge().counters().unattributed - counters_before.unattributed;
  gateway.stop();
  return result;
}

// Bare Fast DDS: the same samples on the same QoS, written back to back by one thread.
std::optional<double> bare_fastdds_writes_per_second(const Options& options) {
  auto participant = teejet::dds::Participant::create(
      {.domain = options.domain, .profile_file = options.profile, .name = "throughput-bare"});
  if (!participant) return std::nullopt;
  auto topic = (*participant)->topic<ValvePositionPubSubType>("bench/throughput/position");
  if (!topic) return std::nullopt;
  auto writer = (*participant)->writer(*topic, teejet::dds::topics::state_writer_qos());
  if (!writer) return std::nullopt;
  ValvePosition sample;
  constexpr int kWrites = 200'000;
  const double cpu0 = this_thread_cpu_seconds();
  for (int i = 0; i < kWrites; ++i) {
    sample.serial(100000u + static_cast<std::uint32_t>(i % kValves));
    sample.degrees(static_cast<float>(i % 900) / 10.0f);
    (*writer)->write(&sample);
  }
  return kWrites / (this_thread_cpu_seconds() - cpu0);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Frames a second through teejet's gateway into DDS without loss "
      "(docs/performance.md). Run inside tests/netns/isolated.",
      "gateway_throughput"};
  Options options;
  app.add_option("--rates", options.rates, "frame rates to try, frames/s")->delimiter(',');
  app.add_option("--seconds", options.seconds, "flood time per rate")->check(CLI::Range(0.1, 60.0));
  app.add_option("--domain", options.domain, "DDS domain id");
  app.add_option("--profile", options.profile, "Fast DDS XML profile file")
      ->check(CLI::ExistingFile);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return app.exit(error) == 0 ? 0 : 2;
  }
  spdlog::set_level(spdlog::level::warn);

  std::printf("%-24s %10s %10s %8s %12s %14s %s\n", "source", "frames/s", "sent", "dropped",
              "us/frame", "reader %core", "result");
  std::printf("%-24s %10.0f %10s %8s %12s %14s %s\n", "500 kbit/s bus (limit)",
              kFullBusFramesPerSecond, "-", "-", "-", "-", "physical limit");
  const auto bare = bare_fastdds_writes_per_second(options);
  if (!bare) {
    std::fprintf(stderr, "gateway_throughput: Fast DDS refused the bare writer\n");
    return 1;
  }
  std::printf("%-24s %10.0f %10s %8s %12.2f %14s %s\n", "bare Fast DDS write", *bare, "-", "-",
              1e6 / *bare, "100", "one thread, back to back");
  double best = 0;
  int round = 0;
  bool failed = false;
  for (const double rate : options.rates) {
    const auto result = run_rate(options, rate, ++round);
    if (!result) {
      failed = true;
      continue;
    }
    const double reader_share = 100.0 * result->reader_cpu_s / result->seconds;
    const double per_frame =
        result->taken > 0 ? 1e6 * result->reader_cpu_s / static_cast<double>(result->taken) : 0;
    std::printf("%-24s %10.0f %10llu %8llu %12.2f %14.1f %s\n", "gateway (bus reader)", rate,
                static_cast<unsigned long long>(result->sent),
                static_cast<unsigned long long>(result->dropped), per_frame, reader_share,
                result->passed() ? "zero loss" : "LOST FRAMES");
    if (result->passed() && rate > best) best = rate;
  }
  std::printf("max zero-loss rate: %.0f frames/s = %.1f x a full 500 kbit/s bus\n", best,
              best / kFullBusFramesPerSecond);
  return failed ? 1 : 0;
}
