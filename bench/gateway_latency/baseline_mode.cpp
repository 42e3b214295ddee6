// baseline and receive modes: bare Fast DDS publish -> receive of the types and QoS the gateway
// path carries, from this process to a child process (`receive`), with no gateway between.
//
// The child reports on descriptor 3: "matched" once its reader matched, then, when it has every
// sample or gave up, one "<sequence> <arrival ns>" line per sample.

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "dds_support.hpp"
#include "in_process_gateway.hpp"
#include "listeners.hpp"
#include "modes.hpp"
#include "series.hpp"

extern char** environ;

namespace teejet::bench {

namespace {

namespace topics = dds::topics;

// The samples the gateway path carries, with a sequence number where the receiver can read it:
// the position in `degrees` (exact in a float up to 2^24), the command in `command_id`.
// The serialized size does not depend on the values, so it matches the gateway's samples.
ValvePosition baseline_position(const Options& options, std::int64_t sequence) {
  ValvePosition sample;
  sample.serial(options.serial);
  sample.degrees(static_cast<float>(sequence));
  sample.received_ns(static_cast<std::uint64_t>(realtime_ns()));
  return sample;
}

ValveCommand baseline_command(const Options& options, std::int64_t sequence) {
  ValveCommand sample;
  sample.serial(options.serial);
  sample.command_id(static_cast<std::uint32_t>(sequence));
  sample.origin("gateway-latency");  // as in gateway mode: same string, same size
  sample.kind(COMMAND_STOP);
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
                                        "--serial",        std::to_string(options.serial),
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

// One series: a writer of Sample's topic here, a receiving child (`receiver_topic` is its
// --topic word), then paced writes from this process.
template <class Sample>
int run_baseline_topic(const Options& options, dds::Participant& participant,
                       const std::string& receiver_topic, const fdds::DataWriterQos& qos,
                       Sample (*make_sample)(const Options&, std::int64_t),
                       const std::string& metric) {
  // The writer first: when it is refused, no child is left waiting for samples.
  auto writer = open_writer<Sample>(participant, qos);
  if (!writer) return fail(writer.error());
  const auto receiver = spawn_receiver(options, receiver_topic);
  if (!receiver) {
    std::fprintf(stderr, "gateway_latency: cannot start the receiving process\n");
    return kExitFailure;
  }
  const auto [receiver_pid, receiver_output] = *receiver;
  std::FILE* lines = ::fdopen(receiver_output, "r");
  // Both sides matched: the writer here, the reader there (it says so first). Before that, a
  // sample can be dropped by a reader that does not know the writer yet.
  char line[64];
  if (!wait_until([&] { return matched(*writer); }, kDiscoveryTimeout) || lines == nullptr ||
      std::fgets(line, sizeof line, lines) == nullptr) {
    std::fprintf(stderr, "gateway_latency: the receiving process never matched\n");
  }
  const int total = options.warmup + options.samples;
  std::vector<std::int64_t> sent(static_cast<std::size_t>(total), 0);
  Pacer pacer(options);
  for (int i = 0; i < total; ++i) {
    Sample sample = make_sample(options, i);
    sent[static_cast<std::size_t>(i)] = realtime_ns();
    (*writer)->write(&sample);
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

template <class Sample>
int receive_topic(const Options& options, const fdds::DataReaderQos& qos,
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
    auto participant = dds::Participant::create({.domain = options.domain,
                                                 .profile_file = options.profile,
                                                 .name = "gateway-latency-baseline-reader"});
    if (!participant) {
      std::fclose(results);
      return fail(participant.error());
    }
    auto reader = open_reader<Sample>(**participant, qos, &log);
    if (!reader) {
      std::fclose(results);
      return fail(reader.error());
    }
    if (wait_until([&] { return matched(*reader); }, kDiscoveryTimeout)) {
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

}  // namespace

int run_baseline(const Options& options) {
  // The same load as `gateway --load-valves`: a busy gateway in this process, and every
  // position it publishes read here, as the ECU of gateway mode reads them.
  auto started = InProcessGateway::start_if_asked(options);
  if (!started) return fail(started.error());
  const std::unique_ptr<InProcessGateway> load = std::move(*started);
  OnSample<ValvePosition> load_positions([](const ValvePosition&) {});
  // One participant for both series: the profile file is loaded once per process (a second
  // load is refused with errors about duplicate transport ids).
  auto participant = dds::Participant::create({.domain = options.domain,
                                               .profile_file = options.profile,
                                               .name = "gateway-latency-baseline-writer"});
  if (!participant) return fail(participant.error());
  if (load) {
    auto reader =
        open_reader<ValvePosition>(**participant, topics::state_reader_qos(), &load_positions);
    if (!reader) return fail(reader.error());
  }
  const int position = run_baseline_topic<ValvePosition>(options, **participant, "position",
                                                         topics::state_writer_qos(),
                                                         &baseline_position, "baseline_position");
  const int command = run_baseline_topic<ValveCommand>(options, **participant, "command",
                                                       topics::command_writer_qos(),
                                                       &baseline_command, "baseline_command");
  return position != 0 ? position : command;
}

// Samples of other serials (a gateway under load on the same domain) are not ours.
int run_receive(const Options& options) {
  if (options.topic == "position") {
    return receive_topic<ValvePosition>(
        options, topics::state_reader_qos(),
        [&](const ValvePosition& sample) -> std::optional<std::int64_t> {
          if (sample.serial() != options.serial) return std::nullopt;
          return std::lround(sample.degrees());
        });
  }
  return receive_topic<ValveCommand>(
      options, topics::command_reader_qos(),
      [&](const ValveCommand& sample) -> std::optional<std::int64_t> {
        if (sample.serial() != options.serial) return std::nullopt;
        return sample.command_id();
      });
}

}  // namespace teejet::bench
