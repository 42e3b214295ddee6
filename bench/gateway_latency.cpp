// gateway_latency: the latency and footprint figures of teejet-gateway (docs/performance.md,
// "Gateway latency and footprint"). bench/run-gateway-bench.sh runs every mode inside
// user-mode-linux and prints the table.
//
// Every mode that creates a DDS participant must run inside tests/uml/uml-run or
// tests/netns/isolated: DDS traffic never leaves the host.
//
//   gateway    command->frame and frame->sample through a running teejet-gateway: this process
//              plays the valve (CAN socket) and the ECU (DDS participant)
//   baseline   bare Fast DDS publish->receive of the same types and QoS, to a child process
//   receive    the baseline's receiving child (started by `baseline`)
//   resources  CPU and memory of running processes over a window, and the bus frame rate
//
// One kernel, one CLOCK_REALTIME for both ends: one-way latencies are differences of two
// readings of the same clock. Results are printed as `KIND key=value ...` lines.

#include <fcntl.h>
#include <spawn.h>
#include <spdlog/spdlog.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <ctime>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "teejet/can/socketcan_bus.hpp"
#include "teejet/codec/codec.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/valvePubSubTypes.h"

extern char** environ;

namespace {

namespace fdds = eprosima::fastdds::dds;
namespace codec = teejet::codec;
namespace topics = teejet::dds::topics;
using ReturnCode = eprosima::fastrtps::types::ReturnCode_t;
using namespace std::chrono_literals;

constexpr int kExitFailure = 1;
// A sample that has not arrived after this long is counted as lost (the pacing gap is 10-20 ms).
constexpr auto kSampleTimeout = 1000ms;
constexpr auto kDiscoveryTimeout = 20s;
// Part number the bench valve announces; any 24-bit value would do.
constexpr std::uint32_t kBenchPartNumber = 0x0BE7C4;

std::int64_t realtime_ns() {
  timespec now{};
  clock_gettime(CLOCK_REALTIME, &now);
  return std::int64_t{now.tv_sec} * 1'000'000'000 + now.tv_nsec;
}

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
};

// ---- Latency series -----------------------------------------------------------------------

struct Series {
  std::string metric;
  std::vector<std::int64_t> latencies_ns;
  std::size_t lost = 0;
};

double percentile_us(const std::vector<std::int64_t>& sorted, double percent) {
  // Nearest rank: the p99 of 1000 samples is the 990th smallest.
  const auto rank =
      static_cast<std::size_t>(std::ceil(percent / 100.0 * static_cast<double>(sorted.size())));
  return static_cast<double>(sorted[std::max<std::size_t>(rank, 1) - 1]) / 1000.0;
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
    std::ofstream raw(options.raw_dir + "/" + options.label + "-" + series.metric + ".ns");
    for (const auto latency : series.latencies_ns) raw << latency << '\n';
  }
}

// Random gaps between samples, so that the measurement never phase-locks with the gateway's own
// periodic work (its 50 ms clock thread, the 1 s status, I'm Here).
class Pacer {
 public:
  explicit Pacer(const Options& options)
      : gap_us_(options.pace_min_ms * 1000, options.pace_max_ms * 1000) {}
  void wait() { std::this_thread::sleep_for(std::chrono::microseconds(gap_us_(random_))); }

 private:
  std::mt19937 random_{20240404};  // fixed: every run paces the same way
  std::uniform_int_distribution<int> gap_us_;
};

// ---- DDS helpers --------------------------------------------------------------------------

bool wait_until(const std::function<bool()>& condition, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!condition()) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(10ms);
  }
  return true;
}

bool matched(fdds::DataWriter* writer) {
  fdds::PublicationMatchedStatus status;
  return writer->get_publication_matched_status(status) == ReturnCode::RETCODE_OK &&
         status.current_count > 0;
}

bool matched(fdds::DataReader* reader) {
  fdds::SubscriptionMatchedStatus status;
  return reader->get_subscription_matched_status(status) == ReturnCode::RETCODE_OK &&
         status.current_count > 0;
}

// Arrival times keyed by a number each sample carries (a sequence number, the position in
// tenths of a degree). The clock is read first thing in the listener: that is "on arrival".
template <class Sample>
class ArrivalLog final : public fdds::DataReaderListener {
 public:
  struct Arrival {
    std::int64_t arrived_ns = 0;
    std::uint64_t carried_ns = 0;  // a time the sample itself carries (received_ns), or 0
  };
  using KeyOf = std::function<std::optional<std::int64_t>(const Sample&)>;
  using CarriedTimeOf = std::function<std::uint64_t(const Sample&)>;

  explicit ArrivalLog(KeyOf key_of, CarriedTimeOf carried_time_of = nullptr)
      : key_of_(std::move(key_of)), carried_time_of_(std::move(carried_time_of)) {}

  void on_data_available(fdds::DataReader* reader) override {
    const std::int64_t arrived = realtime_ns();
    Sample sample;
    fdds::SampleInfo info;
    while (reader->take_next_sample(&sample, &info) == ReturnCode::RETCODE_OK) {
      if (!info.valid_data) continue;
      const auto key = key_of_(sample);
      if (!key) continue;
      std::lock_guard lock(mutex_);
      arrivals_[*key] = {arrived, carried_time_of_ ? carried_time_of_(sample) : 0};
    }
    arrived_.notify_all();
  }

  std::optional<Arrival> wait_for(std::int64_t key, std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    if (!arrived_.wait_for(lock, timeout, [&] { return arrivals_.contains(key); })) {
      return std::nullopt;
    }
    return arrivals_[key];
  }

  std::map<std::int64_t, Arrival> arrivals() const {
    std::lock_guard lock(mutex_);
    return arrivals_;
  }

  void clear() {
    std::lock_guard lock(mutex_);
    arrivals_.clear();
  }

 private:
  const KeyOf key_of_;
  const CarriedTimeOf carried_time_of_;
  mutable std::mutex mutex_;
  std::condition_variable arrived_;
  std::map<std::int64_t, Arrival> arrivals_;
};

// Hands every valid sample to a function, on Fast DDS's listener thread.
template <class Sample>
class OnSample final : public fdds::DataReaderListener {
 public:
  explicit OnSample(std::function<void(const Sample&)> handle) : handle_(std::move(handle)) {}

  void on_data_available(fdds::DataReader* reader) override {
    Sample sample;
    fdds::SampleInfo info;
    while (reader->take_next_sample(&sample, &info) == ReturnCode::RETCODE_OK) {
      if (info.valid_data) handle_(sample);
    }
  }

 private:
  const std::function<void(const Sample&)> handle_;
};

// ---- gateway: command -> frame and frame -> sample ----------------------------------------

// Sends I'm Here for the bench valve once a second (as a real valve does), so the gateway knows
// it and keeps it online (offline after 3 s without).
class Announcer {
 public:
  Announcer(teejet::can::Bus& bus, std::uint8_t address, std::uint32_t serial)
      : thread_([this, &bus, address, serial] {
          const auto frame =
              codec::encode(address, codec::FromValveMessage{codec::IAmHere{
                                         .part_number = kBenchPartNumber, .serial = serial}});
          std::unique_lock lock(mutex_);
          while (!stopping_) {
            if (auto sent = bus.send(*frame); !sent) {
              std::fprintf(stderr, "gateway_latency: I'm Here not sent: %s\n",
                           sent.reason().c_str());
            }
            stop_requested_.wait_for(lock, 1s, [this] { return stopping_; });
          }
        }) {}
  ~Announcer() {
    {
      std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    stop_requested_.notify_all();
    thread_.join();
  }
  Announcer(const Announcer&) = delete;
  Announcer& operator=(const Announcer&) = delete;

 private:
  std::mutex mutex_;
  std::condition_variable stop_requested_;
  bool stopping_ = false;
  std::thread thread_;  // last: starts after the members it uses exist
};

// Calls `one(sequence, measured)` (one sample; true when it arrived) with pacing: first until a
// sample gets through (discovery is complete on both sides only then: a writer can match before
// its reader has), then `warmup` times unmeasured, then `samples` times measured.
void run_series(const Options& options, const std::function<bool(int, bool)>& one) {
  Pacer pacer(options);
  int sequence = 0;
  const auto deadline = std::chrono::steady_clock::now() + kDiscoveryTimeout;
  while (!one(sequence++, false) && std::chrono::steady_clock::now() < deadline) pacer.wait();
  for (int i = 0; i < options.warmup; ++i, ++sequence) {
    pacer.wait();
    one(sequence, false);
  }
  for (int i = 0; i < options.samples; ++i, ++sequence) {
    pacer.wait();
    one(sequence, true);
  }
}

// The kernel receive time of the next Stop frame for `address` stamped at or after `not_before`.
// Other frames (the gateway's poll requests when the valve appears) are skipped.
std::optional<std::int64_t> wait_for_stop_frame(teejet::can::Bus& bus, std::uint8_t address,
                                                std::int64_t not_before) {
  const auto deadline = std::chrono::steady_clock::now() + kSampleTimeout;
  for (;;) {
    const auto left =
        std::chrono::ceil<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left <= 0ms) return std::nullopt;
    const auto received = bus.receive(left);
    if (!received) continue;
    const auto& frame = received->frame;
    const bool stop = frame.id == codec::to_valve_id(address) && frame.dlc >= 1 &&
                      frame.data[0] == codec::message_id(codec::ToValveMessage{codec::Stop{}});
    if (stop && received->received.count() >= not_before) return received->received.count();
  }
}

int run_gateway(const Options& options) {
  const auto address = static_cast<std::uint8_t>(options.address);
  if (!codec::is_valve_address(address)) {
    std::fprintf(stderr, "gateway_latency: --address must be 0xD8..0xF7\n");
    return kExitFailure;
  }
  // Only frames for the bench valve: the gateway's frames to other (simulated) valves stay in
  // the kernel.
  teejet::can::SocketCanBus bus(options.can,
                                {.filters = {{codec::to_valve_id(address), 0x1FFFFFFF}}});
  if (auto opened = bus.open(); !opened) {
    std::fprintf(stderr, "gateway_latency: %s\n", opened.reason().c_str());
    return kExitFailure;
  }
  const Announcer announcer(bus, address, options.serial);

  // Listeners outlive the participant that calls them: declared first, destroyed last.
  std::atomic<bool> valve_online{false};
  OnSample<teejet::ValvePresence> presence([&](const teejet::ValvePresence& sample) {
    if (sample.serial() == options.serial) valve_online = sample.online();
  });
  // Position samples of the bench valve keyed by tenths of a degree, with the CAN receive time
  // the gateway put in received_ns.
  ArrivalLog<teejet::ValvePosition> positions(
      [&](const teejet::ValvePosition& sample) -> std::optional<std::int64_t> {
        if (sample.serial() != options.serial) return std::nullopt;
        return std::lround(sample.degrees() * 10.0F);
      },
      [](const teejet::ValvePosition& sample) { return sample.received_ns(); });
  // CommandStatus ACCEPTED keyed by command id. Its stamp_ns is the gateway's clock reading
  // when its reader handed the command over: it splits command -> frame into DDS delivery and
  // the gateway's own work (validate, encode, send).
  ArrivalLog<teejet::CommandStatus> accepted(
      [&](const teejet::CommandStatus& status) -> std::optional<std::int64_t> {
        if (status.serial() != options.serial || status.state() != teejet::COMMAND_ACCEPTED) {
          return std::nullopt;
        }
        return status.command_id();
      },
      [](const teejet::CommandStatus& status) { return status.stamp_ns(); });

  teejet::dds::Participant participant(
      {.domain = options.domain, .profile_file = options.profile, .name = "gateway-latency-ecu"});
  participant.reader(participant.topic<teejet::ValvePresencePubSubType>(topics::kPresence),
                     topics::state_reader_qos(), &presence);
  auto* position_reader =
      participant.reader(participant.topic<teejet::ValvePositionPubSubType>(topics::kPosition),
                         topics::state_reader_qos(), &positions);
  participant.reader(participant.topic<teejet::CommandStatusPubSubType>(topics::kCommandStatus),
                     topics::status_reader_qos(), &accepted);
  auto* command_writer =
      participant.writer(participant.topic<teejet::ValveCommandPubSubType>(topics::kCommand),
                         topics::command_writer_qos());

  if (!wait_until(
          [&] { return valve_online && matched(command_writer) && matched(position_reader); },
          kDiscoveryTimeout)) {
    std::fprintf(stderr,
                 "gateway_latency: no gateway on domain %d knows the bench valve after %lld s "
                 "(online %d, command writer matched %d, position reader matched %d)\n",
                 options.domain, static_cast<long long>(kDiscoveryTimeout.count()),
                 valve_online.load(), matched(command_writer), matched(position_reader));
    return kExitFailure;
  }

  // command -> frame: DataWriter::write(Stop) until the Stop frame's kernel receive stamp on
  // our socket.
  Series command_to_frame{"command_to_frame", {}, 0};
  std::map<std::int64_t, std::pair<std::int64_t, std::int64_t>> command_times;  // id: sent, frame
  teejet::ValveCommand command;
  command.serial(options.serial);
  command.origin("gateway-latency");
  command.kind(teejet::COMMAND_STOP);
  run_series(options, [&](int sequence, bool measured) {
    while (bus.receive(0ms)) {
      // Drop what came before t0 (poll requests, a late Stop) so it cannot be matched.
    }
    const auto id = static_cast<std::uint32_t>(sequence + 1);
    command.command_id(id);
    const std::int64_t sent = realtime_ns();
    command_writer->write(&command);
    const auto frame = wait_for_stop_frame(bus, address, sent);
    if (measured && frame) {
      command_to_frame.latencies_ns.push_back(*frame - sent);
      command_times[id] = {sent, *frame};
    } else if (measured) {
      ++command_to_frame.lost;
    }
    return frame.has_value();
  });

  // frame -> sample: write() of a Position frame on our socket until the ECU's listener runs.
  Series frame_to_sample{"frame_to_sample", {}, 0};
  Series frame_to_gateway_socket{"frame_to_gateway_socket", {}, 0};
  Series gateway_socket_to_sample{"gateway_socket_to_sample", {}, 0};
  run_series(options, [&](int sequence, bool measured) {
    // Each sample differs from the previous one, so a late sample is never taken for this one.
    const int tenths = sequence % 3600;
    const auto frame =
        codec::encode(address, codec::FromValveMessage{codec::Position{.degrees = tenths / 10.0}});
    positions.clear();
    const std::int64_t sent = realtime_ns();
    if (auto written = bus.send(*frame); !written) {
      std::fprintf(stderr, "gateway_latency: Position not sent: %s\n", written.reason().c_str());
    }
    const auto arrival = positions.wait_for(tenths, kSampleTimeout);
    if (measured && arrival) {
      const auto gateway_socket = static_cast<std::int64_t>(arrival->carried_ns);
      frame_to_sample.latencies_ns.push_back(arrival->arrived_ns - sent);
      frame_to_gateway_socket.latencies_ns.push_back(gateway_socket - sent);
      gateway_socket_to_sample.latencies_ns.push_back(arrival->arrived_ns - gateway_socket);
    } else if (measured) {
      ++frame_to_sample.lost;
    }
    return arrival.has_value();
  });

  // The ACCEPTED statuses of the last commands had seconds to arrive meanwhile.
  Series command_to_gateway{"command_to_gateway", {}, 0};
  Series gateway_to_frame{"gateway_to_frame", {}, 0};
  const auto statuses = accepted.arrivals();
  for (const auto& [id, times] : command_times) {
    const auto status = statuses.find(id);
    if (status == statuses.end()) {
      ++command_to_gateway.lost;
      continue;
    }
    const auto gateway_got = static_cast<std::int64_t>(status->second.carried_ns);
    command_to_gateway.latencies_ns.push_back(gateway_got - times.first);
    gateway_to_frame.latencies_ns.push_back(times.second - gateway_got);
  }

  for (const Series* series :
       {&command_to_frame, &command_to_gateway, &gateway_to_frame, &frame_to_sample,
        &frame_to_gateway_socket, &gateway_socket_to_sample}) {
    report(*series, options);
  }
  return 0;
}

// ---- baseline: bare Fast DDS between two processes ---------------------------------------

// The samples the gateway path carries, with a sequence number where the receiver can read it:
// the position in `degrees` (exact in a float up to 2^24), the command in `command_id`.
// The serialized size does not depend on the values, so it matches the gateway's samples.
teejet::ValvePosition baseline_position(const Options& options, std::int64_t sequence) {
  teejet::ValvePosition sample;
  sample.serial(options.serial);
  sample.degrees(static_cast<float>(sequence));
  sample.received_ns(static_cast<std::uint64_t>(realtime_ns()));
  return sample;
}

teejet::ValveCommand baseline_command(const Options& options, std::int64_t sequence) {
  teejet::ValveCommand sample;
  sample.serial(options.serial);
  sample.command_id(static_cast<std::uint32_t>(sequence));
  sample.origin("gateway-latency");  // as in gateway mode: same string, same size
  sample.kind(teejet::COMMAND_STOP);
  return sample;
}

// The receiving child writes its arrival times here, not on stdout: Fast DDS logs to stdout.
constexpr int kReceiverResultFd = 3;

// Starts `/proc/self/exe receive ...` with its result descriptor on a pipe; returns the pid and
// the pipe's read end. posix_spawn, not fork: Fast DDS threads are running (fork in a threaded
// process is a trap).
std::optional<std::pair<pid_t, int>> spawn_receiver(const Options& options,
                                                    const std::string& topic) {
  int pipe_ends[2];
  if (::pipe2(pipe_ends, O_CLOEXEC) != 0) return std::nullopt;
  const int total = options.warmup + options.samples;
  const int timeout_s = 30 + total * options.pace_max_ms / 1000;
  std::vector<std::string> arguments = {"gateway_latency", "receive",
                                        "--topic",         topic,
                                        "--domain",        std::to_string(options.domain),
                                        "--count",         std::to_string(total),
                                        "--timeout-s",     std::to_string(timeout_s)};
  if (!options.profile.empty()) {
    arguments.push_back("--profile");
    arguments.push_back(options.profile);
  }
  std::vector<char*> argv;
  for (auto& argument : arguments) argv.push_back(argument.data());
  argv.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, pipe_ends[1], kReceiverResultFd);
  pid_t pid = 0;
  const int failed = posix_spawn(&pid, "/proc/self/exe", &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(pipe_ends[1]);
  if (failed != 0) {
    ::close(pipe_ends[0]);
    return std::nullopt;
  }
  return std::make_pair(pid, pipe_ends[0]);
}

// One series: a receiving child for `topic_name` (`receiver_topic` is its --topic word), then
// paced writes from this process.
template <class PubSubType, class Sample>
int run_baseline_topic(const Options& options, teejet::dds::Participant& participant,
                       const char* topic_name, const std::string& receiver_topic,
                       const fdds::DataWriterQos& qos,
                       Sample (*make_sample)(const Options&, std::int64_t),
                       const std::string& metric) {
  const auto receiver = spawn_receiver(options, receiver_topic);
  if (!receiver) {
    std::fprintf(stderr, "gateway_latency: cannot start the receiving process\n");
    return kExitFailure;
  }
  const auto [receiver_pid, receiver_output] = *receiver;
  auto* writer = participant.writer(participant.topic<PubSubType>(topic_name), qos);
  std::FILE* lines = ::fdopen(receiver_output, "r");
  // Both sides matched: the writer here, the reader there (it says so first). Before that, a
  // sample can be dropped by a reader that does not know the writer yet.
  char line[64];
  if (!wait_until([&] { return matched(writer); }, kDiscoveryTimeout) || lines == nullptr ||
      std::fgets(line, sizeof line, lines) == nullptr) {
    std::fprintf(stderr, "gateway_latency: the receiving process never matched\n");
  }
  const int total = options.warmup + options.samples;
  std::vector<std::int64_t> sent(static_cast<std::size_t>(total), 0);
  Pacer pacer(options);
  for (int i = 0; i < total; ++i) {
    Sample sample = make_sample(options, i);
    sent[static_cast<std::size_t>(i)] = realtime_ns();
    writer->write(&sample);
    pacer.wait();
  }

  // The writer stays until the receiver has everything: it exits then, closing the pipe.
  Series series{metric, {}, 0};
  std::vector<bool> seen(static_cast<std::size_t>(total), false);
  while (lines != nullptr && std::fgets(line, sizeof line, lines) != nullptr) {
    long long sequence = 0, arrived = 0;
    if (std::sscanf(line, "%lld %lld", &sequence, &arrived) != 2) continue;
    if (sequence < options.warmup || sequence >= total) continue;
    seen[static_cast<std::size_t>(sequence)] = true;
    series.latencies_ns.push_back(arrived - sent[static_cast<std::size_t>(sequence)]);
  }
  if (lines != nullptr) std::fclose(lines);
  series.lost =
      static_cast<std::size_t>(std::count(seen.begin() + options.warmup, seen.end(), false));
  report(series, options);

  int status = 0;
  ::waitpid(receiver_pid, &status, 0);
  return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? 0 : kExitFailure;
}

int run_baseline(const Options& options) {
  // One participant for both series: the profile file is loaded once per process (a second
  // load is refused with errors about duplicate transport ids).
  teejet::dds::Participant participant({.domain = options.domain,
                                        .profile_file = options.profile,
                                        .name = "gateway-latency-baseline-writer"});
  const int position = run_baseline_topic<teejet::ValvePositionPubSubType>(
      options, participant, topics::kPosition, "position", topics::state_writer_qos(),
      &baseline_position, "baseline_position");
  const int command = run_baseline_topic<teejet::ValveCommandPubSubType>(
      options, participant, topics::kCommand, "command", topics::command_writer_qos(),
      &baseline_command, "baseline_command");
  return position != 0 ? position : command;
}

template <class PubSubType, class Sample>
int receive_topic(const Options& options, const char* topic_name, const fdds::DataReaderQos& qos,
                  std::function<std::optional<std::int64_t>(const Sample&)> sequence_of) {
  std::FILE* results = ::fdopen(kReceiverResultFd, "w");
  if (results == nullptr) {
    std::fprintf(stderr,
                 "gateway_latency receive: descriptor %d is not open (started by "
                 "`baseline` only)\n",
                 kReceiverResultFd);
    return kExitFailure;
  }
  ArrivalLog<Sample> log(std::move(sequence_of));
  {
    teejet::dds::Participant participant({.domain = options.domain,
                                          .profile_file = options.profile,
                                          .name = "gateway-latency-baseline-reader"});
    auto* reader = participant.reader(participant.topic<PubSubType>(topic_name), qos, &log);
    if (wait_until([&] { return matched(reader); }, kDiscoveryTimeout)) {
      std::fputs("matched\n", results);
      std::fflush(results);
    }
    const auto last = static_cast<std::int64_t>(options.count - 1);
    if (!log.wait_for(last, std::chrono::seconds(options.timeout_s))) {
      std::fprintf(stderr, "gateway_latency receive: the last sample did not arrive\n");
    }
  }
  for (const auto& [sequence, arrival] : log.arrivals()) {
    std::fprintf(results, "%lld %lld\n", static_cast<long long>(sequence),
                 static_cast<long long>(arrival.arrived_ns));
  }
  std::fclose(results);
  return 0;
}

int run_receive(const Options& options) {
  if (options.topic == "position") {
    return receive_topic<teejet::ValvePositionPubSubType, teejet::ValvePosition>(
        options, topics::kPosition, topics::state_reader_qos(),
        [](const teejet::ValvePosition& sample) {
          return std::optional<std::int64_t>(std::lround(sample.degrees()));
        });
  }
  return receive_topic<teejet::ValveCommandPubSubType, teejet::ValveCommand>(
      options, topics::kCommand, topics::command_reader_qos(),
      [](const teejet::ValveCommand& sample) {
        return std::optional<std::int64_t>(sample.command_id());
      });
}

// ---- resources: CPU and memory over a window ---------------------------------------------

std::string read_file(const std::string& path) {
  std::ifstream file(path);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

// utime + stime of a process in clock ticks (fields 14 and 15 of /proc/PID/stat; the command
// name in field 2 may contain spaces, so fields are counted after its closing parenthesis).
std::optional<std::uint64_t> cpu_ticks(int pid) {
  const std::string stat = read_file("/proc/" + std::to_string(pid) + "/stat");
  const auto name_end = stat.rfind(')');
  if (name_end == std::string::npos) return std::nullopt;
  std::istringstream fields(stat.substr(name_end + 2));
  std::string field;
  std::uint64_t user = 0, system = 0;
  for (int number = 3; number <= 15 && fields >> field; ++number) {
    if (number == 14) user = std::stoull(field);
    if (number == 15) system = std::stoull(field);
  }
  return user + system;
}

// A "Name:   value kB" line of /proc/PID/status, in KiB.
std::uint64_t status_kib(int pid, const std::string& name) {
  std::istringstream status(read_file("/proc/" + std::to_string(pid) + "/status"));
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind(name + ":", 0) == 0) return std::stoull(line.substr(name.size() + 1));
  }
  return 0;
}

std::string process_name(int pid) {
  std::string name = read_file("/proc/" + std::to_string(pid) + "/comm");
  if (!name.empty() && name.back() == '\n') name.pop_back();
  return name;
}

// Frames the interface carried (vcan counts every frame sent on it as tx).
std::optional<std::uint64_t> bus_frames(const std::string& interface) {
  const std::string count = read_file("/sys/class/net/" + interface + "/statistics/tx_packets");
  if (count.empty()) return std::nullopt;
  return std::stoull(count);
}

// The gateway's own counters, from one GatewayStatus sample.
struct GatewayCounters {
  std::uint64_t frames_in = 0;
  std::uint64_t frames_out = 0;
  std::uint64_t stamp_ns = 0;
};

// An ECU reading every topic the gateway writes, so the gateway's writers deliver (with no
// reader matched, a write ends inside the gateway) and the window measures a working gateway.
class EcuReadingEverything {
 public:
  explicit EcuReadingEverything(const Options& options)
      : participant_({.domain = options.domain,
                      .profile_file = options.profile,
                      .name = "gateway-latency-ecu"}) {
    participant_.reader(participant_.topic<teejet::ValvePresencePubSubType>(topics::kPresence),
                        topics::state_reader_qos(), &presence_);
    count<teejet::ValvePositionPubSubType, teejet::ValvePosition>(topics::kPosition);
    count<teejet::ValveVersionPubSubType, teejet::ValveVersion>(topics::kVersion);
    count<teejet::ValveTemperaturePubSubType, teejet::ValveTemperature>(topics::kTemperature);
    count<teejet::ValveVoltagePubSubType, teejet::ValveVoltage>(topics::kVoltage);
    count<teejet::ValveCurrentPubSubType, teejet::ValveCurrent>(topics::kCurrent);
    count<teejet::ValveDegreesPerSecondPubSubType, teejet::ValveDegreesPerSecond>(
        topics::kDegreesPerSecond);
    count<teejet::ValveSpeedDirectionPubSubType, teejet::ValveSpeedDirection>(
        topics::kSpeedDirection);
    count<teejet::ValveRunTimePubSubType, teejet::ValveRunTime>(topics::kRunTime);
    count<teejet::ValveCycleCountPubSubType, teejet::ValveCycleCount>(topics::kCycleCount);
    count<teejet::ValveBaudRatePubSubType, teejet::ValveBaudRate>(topics::kBaudRate);
    count<teejet::ValveErrorPubSubType, teejet::ValveError>(topics::kError);
    participant_.reader(participant_.topic<teejet::GatewayStatusPubSubType>(topics::kGatewayStatus),
                        topics::state_reader_qos(), &gateway_status_);
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

 private:
  template <class PubSubType, class Sample>
  void count(const char* topic_name) {
    auto counter = std::make_shared<OnSample<Sample>>([this](const Sample&) { ++samples_; });
    participant_.reader(participant_.topic<PubSubType>(topic_name), topics::state_reader_qos(),
                        counter.get());
    counters_.push_back(counter);
  }

  std::atomic<std::uint64_t> samples_{0};
  mutable std::mutex mutex_;
  std::optional<GatewayCounters> gateway_counters_;
  std::set<std::uint32_t> serials_seen_;
  OnSample<teejet::ValvePresence> presence_{[this](const teejet::ValvePresence& sample) {
    ++samples_;
    std::lock_guard lock(mutex_);
    serials_seen_.insert(sample.serial());
  }};
  OnSample<teejet::GatewayStatus> gateway_status_{[this](const teejet::GatewayStatus& status) {
    std::lock_guard lock(mutex_);
    gateway_counters_ = GatewayCounters{status.frames_in(), status.frames_out(), status.stamp_ns()};
  }};
  std::vector<std::shared_ptr<fdds::DataReaderListener>> counters_;
  teejet::dds::Participant participant_;  // last: destroyed first, before the listeners it calls
};

int run_resources(const Options& options) {
  std::unique_ptr<EcuReadingEverything> ecu;
  if (options.subscribe) ecu = std::make_unique<EcuReadingEverything>(options);
  // Discovery, the late-joiner burst and the gateway's start-up are not part of the window.
  std::this_thread::sleep_for(std::chrono::duration<double>(options.settle_s));

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
  const auto gateway_before = ecu ? ecu->gateway_counters() : std::nullopt;
  const auto window_start = std::chrono::steady_clock::now();

  std::this_thread::sleep_for(std::chrono::duration<double>(options.window_s));

  const double window =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - window_start).count();
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
        static_cast<unsigned long long>(status_kib(start.pid, "VmRSS")),
        static_cast<unsigned long long>(status_kib(start.pid, "VmHWM")));
  }
  if (frames_before) {
    const auto frames_after = bus_frames(options.interface);
    std::printf("BUS label=%s interface=%s frames_per_s=%.1f\n", options.label.c_str(),
                options.interface.c_str(),
                static_cast<double>(frames_after.value_or(0) - *frames_before) / window);
  }
  if (ecu) {
    std::printf("SUBSCRIBER label=%s samples_per_s=%.1f valves_seen=%zu", options.label.c_str(),
                static_cast<double>(ecu->samples() - samples_before) / window, ecu->valves_seen());
    const auto gateway_after = ecu->gateway_counters();
    if (gateway_before && gateway_after && gateway_after->stamp_ns > gateway_before->stamp_ns) {
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
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Latency and footprint of teejet-gateway (docs/performance.md). Modes that use DDS "
      "must run in tests/uml/uml-run or tests/netns/isolated.",
      "gateway_latency"};
  app.require_subcommand(1);
  Options options;

  const auto add_dds = [&](CLI::App* mode) {
    mode->add_option("--domain", options.domain, "DDS domain id");
    mode->add_option("--profile", options.profile, "Fast DDS XML profile file")
        ->check(CLI::ExistingFile);
  };
  const auto add_series = [&](CLI::App* mode) {
    mode->add_option("--label", options.label, "name of this run in the output");
    mode->add_option("--samples", options.samples, "measured samples per series");
    mode->add_option("--warmup", options.warmup, "samples sent first and not measured");
    mode->add_option("--pace-min-ms", options.pace_min_ms, "shortest gap between samples");
    mode->add_option("--pace-max-ms", options.pace_max_ms, "longest gap between samples");
    mode->add_option("--raw-dir", options.raw_dir, "write every latency (ns) to files here");
    mode->add_option("--serial", options.serial, "serial of the bench valve");
  };

  auto* gateway = app.add_subcommand(
      "gateway", "command->frame and frame->sample through a running teejet-gateway");
  add_dds(gateway);
  add_series(gateway);
  gateway->add_option("--can", options.can, "CAN interface the gateway is on");
  gateway->add_option("--address", options.address,
                      "CAN address of the bench valve (0xD8..0xF7); free of simulated valves");

  auto* baseline = app.add_subcommand(
      "baseline", "bare Fast DDS publish->receive of ValvePosition and ValveCommand");
  add_dds(baseline);
  add_series(baseline);

  auto* receive = app.add_subcommand("receive", "the baseline's receiving process (internal)");
  add_dds(receive);
  receive->add_option("--topic", options.topic)
      ->required()
      ->check(CLI::IsMember({"position", "command"}));
  receive->add_option("--count", options.count)->required();
  receive->add_option("--timeout-s", options.timeout_s);

  auto* resources = app.add_subcommand(
      "resources", "CPU and memory of processes over a window, and the bus frame rate");
  add_dds(resources);
  resources->add_option("--label", options.label, "name of this run in the output");
  resources->add_option("--pid", options.pids, "process to measure (repeatable)")->required();
  resources->add_option("--window-s", options.window_s, "measured window");
  resources->add_option("--settle-s", options.settle_s, "wait before the window");
  resources->add_option("--interface", options.interface, "count the frames on this interface");
  resources->add_flag("--subscribe", options.subscribe,
                      "read every gateway topic meanwhile, as an ECU would");

  CLI11_PARSE(app, argc, argv);
  // The CAN layer logs opening and closing at info; the output here is the results only.
  spdlog::set_level(spdlog::level::warn);
  if (options.pace_min_ms < 0 || options.pace_max_ms < options.pace_min_ms || options.samples < 1 ||
      options.warmup < 0) {
    std::fprintf(stderr, "gateway_latency: bad --samples/--warmup/--pace-*-ms\n");
    return 2;
  }
  try {
    if (*gateway) return run_gateway(options);
    if (*baseline) return run_baseline(options);
    if (*receive) return run_receive(options);
    return run_resources(options);
  } catch (const teejet::dds::DdsError& error) {
    std::fprintf(stderr, "gateway_latency: %s\n", error.what());
    return kExitFailure;
  }
}
