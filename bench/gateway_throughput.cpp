// gateway_throughput: how many frames a second the gateway takes from the bus into DDS without
// losing one, and what each frame costs its bus reader thread, beside bare Fast DDS writing the
// same samples and the physical limit of a 500 kbit/s bus (docs/performance.md, "Throughput").
//
// In-process: a real gateway::Gateway (bridge, DDS writers, its reader thread) on a virtual
// bus, and a flood endpoint on the same bus that announces 32 valves (I'm Here) and then sends
// Position frames round-robin, paced in 1 ms bursts, at each rate asked for. A rate passes when
// every frame sent was taken off the bus (none dropped by the bounded receive queue) and
// attributed to its valve. Creates a DDS participant: run it inside tests/netns/isolated.
// With --can vcan0 (inside user-mode-linux: tests/uml/uml-run) the gateway reads a real
// SocketCAN socket and the flood comes from a second raw socket; the kernel's drop counter
// (SO_RXQ_OVFL) then counts what the gateway's socket could not hold.

#include <spdlog/spdlog.h>
#include <time.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "teejet/can/open_bus.hpp"
#include "teejet/can/virtual_bus.hpp"
#include "teejet/codec/can_id.hpp"
#include "teejet/codec/codec.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/gateway/gateway.hpp"
#include "teejet/valvePubSubTypes.h"

namespace {

using namespace teejet;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

constexpr int kValves = 32;
// A 500 kbit/s bus: an extended frame with 8 data bytes is 128 bits before stuffing, up to 153
// with worst-case stuffing, plus 3 bits of interframe space: 3,200 to 3,800 frames a second.
constexpr double kFullBusFramesPerSecond = 500'000.0 / 131.0;

enum class Arrival { kBursts, kEven };

struct Options {
  std::vector<double> rates{4'000, 20'000, 80'000, 160'000, 320'000};
  double seconds = 2.0;
  // Flooded before the measured seconds: the gateway judges a bus busy enough to coalesce only
  // after a second of it (gateway.receive_coalesce_above_fps), as a bus runs for hours.
  double settle_seconds = 1.5;
  Arrival arrival = Arrival::kBursts;
  std::vector<int> coalesce_us{0};
  std::string can;  // a SocketCAN interface (vcan0 in user-mode-linux); empty: the virtual bus
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

double cpu_seconds(clockid_t clock) {
  timespec now{};
  ::clock_gettime(clock, &now);
  return static_cast<double>(now.tv_sec) + static_cast<double>(now.tv_nsec) / 1e9;
}

double this_thread_cpu_seconds() { return cpu_seconds(CLOCK_THREAD_CPUTIME_ID); }

// Everything the gateway's threads and Fast DDS's used: the process minus this (flooding) thread.
double gateway_cpu_seconds() {
  return cpu_seconds(CLOCK_PROCESS_CPUTIME_ID) - this_thread_cpu_seconds();
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
  std::uint64_t taken_measured = 0;  // after the settling
  std::uint64_t dropped = 0;
  std::uint64_t unattributed = 0;
  double reader_cpu_s = 0;
  double gateway_cpu_s = 0;
  double seconds = 0;
  bool passed() const { return dropped == 0 && unattributed == 0 && taken == sent; }
};

std::optional<RateResult> run_rate(const Options& options, double rate, int coalesce_us,
                                   int round) {
  const std::string bus_name =
      "throughput-" + std::to_string(::getpid()) + "-" + std::to_string(round);
  gateway::GatewayConfig config;
  config.can = options.can.empty() ? "virtual:" + bus_name : options.can;
  config.domain = options.domain;
  config.profile_file = options.profile;
  config.stop_valves_on_exit = false;
  config.receive_coalesce = std::chrono::microseconds(coalesce_us);
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
  std::unique_ptr<can::Bus> flood_bus =
      options.can.empty()
          ? std::make_unique<can::VirtualBus>(
                bus_name,
                can::VirtualBusOptions{.filters = can::valve_side_filters(), .queue_limit = 16})
          : can::make_bus(options.can, can::valve_side_filters());
  can::Bus& flood = *flood_bus;
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
  const auto start = Clock::now();
  const auto settled = start + std::chrono::duration_cast<Clock::duration>(
                                   std::chrono::duration<double>(options.settle_seconds));
  const auto end = settled + std::chrono::duration_cast<Clock::duration>(
                                 std::chrono::duration<double>(options.seconds));
  std::optional<Clock::time_point> measured_from;
  double reader_cpu0 = 0;
  double gateway_cpu0 = 0;
  std::uint64_t taken_before_measuring = 0;
  // Bursts: whatever is due, once a millisecond. Even: one frame at a time, as a real bus
  // delivers them (a vcan or the virtual bus has no bit time of its own).
  const auto step =
      options.arrival == Arrival::kBursts
          ? Clock::duration(1ms)
          : std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / rate));
  std::vector<codec::CanFrame> burst;
  std::uint64_t sequence = 0;
  auto next = start;
  while (next < end) {
    if (!measured_from && next >= settled) {
      measured_from = Clock::now();
      reader_cpu0 = thread_cpu_seconds(*reader);
      gateway_cpu0 = gateway_cpu_seconds();
      taken_before_measuring = gateway_bus->statistics().frames_in;
    }
    const double due_by = rate * std::chrono::duration<double>(next + step - start).count();
    burst.clear();
    while (static_cast<double>(result.sent + burst.size()) < due_by) {
      const int valve = static_cast<int>(sequence % kValves);
      const double degrees = static_cast<double>((sequence / kValves) % 900) / 10.0;
      burst.push_back(frame_of(address_of(valve), codec::Position{degrees}));
      ++sequence;
    }
    result.sent += flood.send_batch(burst).sent;
    next += step;
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
  if (!measured_from) {  // a rate so low that no frame fell after the settling
    std::fprintf(stderr, "gateway_throughput: %.0f frames/s sent nothing to measure\n", rate);
    return std::nullopt;
  }
  result.seconds = std::chrono::duration<double>(Clock::now() - *measured_from).count();
  result.reader_cpu_s = thread_cpu_seconds(*reader) - reader_cpu0;
  result.gateway_cpu_s = gateway_cpu_seconds() - gateway_cpu0;
  result.taken = now_stats.frames_in - before.frames_in;
  result.taken_measured = now_stats.frames_in - taken_before_measuring;
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
  // 200,000 writes, or what two seconds allow (user-mode-linux manages a few thousand).
  constexpr int kWrites = 200'000;
  const auto give_up = Clock::now() + 2s;
  const double cpu0 = this_thread_cpu_seconds();
  int written = 0;
  while (written < kWrites && (written % 1000 != 0 || Clock::now() < give_up)) {
    sample.serial(100000u + static_cast<std::uint32_t>(written % kValves));
    sample.degrees(static_cast<float>(written % 900) / 10.0f);
    (*writer)->write(&sample);
    ++written;
  }
  return written / (this_thread_cpu_seconds() - cpu0);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Frames a second through teejet's gateway into DDS without loss "
      "(docs/performance.md). Run inside tests/netns/isolated.",
      "gateway_throughput"};
  Options options;
  app.add_option("--rates", options.rates, "frame rates to try, frames/s")->delimiter(',');
  app.add_option("--seconds", options.seconds, "measured flood time per rate")
      ->check(CLI::Range(0.1, 60.0));
  app.add_option("--settle-seconds", options.settle_seconds,
                 "flood time before the measured seconds (not measured)")
      ->check(CLI::Range(0.0, 60.0));
  app.add_option("--arrival", options.arrival,
                 "bursts: what is due once a millisecond; even: one frame at a time")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, Arrival>{{"bursts", Arrival::kBursts}, {"even", Arrival::kEven}}));
  app.add_option("--coalesce-us", options.coalesce_us,
                 "gateway.receive_coalesce_us values to try at every rate")
      ->delimiter(',')
      ->check(CLI::Range(0, 10'000));
  app.add_option("--can", options.can,
                 "flood a SocketCAN interface (vcan0, inside user-mode-linux) through a raw "
                 "socket instead of the in-process virtual bus");
  app.add_option("--domain", options.domain, "DDS domain id");
  app.add_option("--profile", options.profile, "Fast DDS XML profile file")
      ->check(CLI::ExistingFile);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return app.exit(error) == 0 ? 0 : 2;
  }
  spdlog::set_level(spdlog::level::warn);

  const char* const row = "%-28s %9s %9s %9s %9s %8s %9s %8s %9s  %s\n";
  std::printf(row, "source", "frames/s", "coalesce", "sent", "taken", "dropped", "us/frame",
              "reader", "gateway", "result");
  std::printf(row, "", "", "us", "", "", "", "(reader)", "%core", "%core", "");
  std::printf(row, "500 kbit/s bus (limit)", fmt::format("{:.0f}", kFullBusFramesPerSecond).c_str(),
              "", "", "", "", "", "", "", "physical limit");
  const auto bare = bare_fastdds_writes_per_second(options);
  if (!bare) {
    std::fprintf(stderr, "gateway_throughput: Fast DDS refused the bare writer\n");
    return 1;
  }
  std::printf(row, "bare Fast DDS write", fmt::format("{:.0f}", *bare).c_str(), "", "", "", "",
              fmt::format("{:.2f}", 1e6 / *bare).c_str(), "100", "", "one thread, back to back");
  const char* const arrival = options.arrival == Arrival::kBursts ? "1 ms bursts" : "even";
  double best = 0;
  int round = 0;
  bool failed = false;
  for (const double rate : options.rates) {
    for (const int coalesce_us : options.coalesce_us) {
      const auto result = run_rate(options, rate, coalesce_us, ++round);
      if (!result) {
        failed = true;
        continue;
      }
      const double taken = static_cast<double>(std::max<std::uint64_t>(result->taken_measured, 1));
      std::printf(
          row,
          fmt::format("gateway, {}{}", options.can.empty() ? "" : options.can + ", ", arrival)
              .c_str(),
          fmt::format("{:.0f}", rate).c_str(), std::to_string(coalesce_us).c_str(),
          std::to_string(result->sent).c_str(), std::to_string(result->taken).c_str(),
          std::to_string(result->dropped).c_str(),
          fmt::format("{:.2f}", 1e6 * result->reader_cpu_s / taken).c_str(),
          fmt::format("{:.1f}", 100.0 * result->reader_cpu_s / result->seconds).c_str(),
          fmt::format("{:.1f}", 100.0 * result->gateway_cpu_s / result->seconds).c_str(),
          result->passed() ? "zero loss" : "LOST FRAMES");
      if (result->passed() && rate > best) best = rate;
    }
  }
  std::printf("max zero-loss rate: %.0f frames/s = %.1f x a full 500 kbit/s bus\n", best,
              best / kFullBusFramesPerSecond);
  return failed ? 1 : 0;
}
