// gateway mode: command -> frame and frame -> sample through a running teejet-gateway. This
// process plays the valve (a CAN socket) and the ECU (a DDS participant). With --load-valves
// the gateway runs in this process on a virtual bus with simulated valves beside the bench
// valve (in_process_gateway.hpp), for the host.

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>

#include "dds_support.hpp"
#include "in_process_gateway.hpp"
#include "listeners.hpp"
#include "modes.hpp"
#include "series.hpp"
#include "teejet/can/socketcan_bus.hpp"
#include "teejet/codec/codec.hpp"

namespace teejet::bench {

namespace {

namespace topics = dds::topics;
using namespace std::chrono_literals;

// A sample that has not arrived after this long is counted as lost (the pacing gap is 10-20 ms).
constexpr auto kSampleTimeout = 1000ms;
// Part number the bench valve announces; any 24-bit value would do.
constexpr std::uint32_t kBenchPartNumber = 0x0BE7C4;

// Sends I'm Here for the bench valve once a second (as a real valve does), so the gateway knows
// it and keeps it online (offline after 3 s without).
class Announcer {
 public:
  Announcer(can::Bus& bus, std::uint8_t address, std::uint32_t serial)
      : thread_([this, &bus, address, serial] {
          const auto frame =
              codec::encode(address, codec::FromValveMessage{codec::IAmHere{
                                         .part_number = kBenchPartNumber, .serial = serial}});
          std::unique_lock lock(mutex_);
          while (!stopping_) {
            if (auto sent = bus.send(*frame); !sent) {
              std::fprintf(stderr, "gateway_latency: I'm Here not sent: %s\n",
                           sent.error().reason.c_str());
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
std::optional<std::int64_t> wait_for_stop_frame(can::Bus& bus, std::uint8_t address,
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
    const std::int64_t stamp = received->received.time_since_epoch().count();
    if (stop && stamp >= not_before) return stamp;
  }
}

}  // namespace

int run_gateway(const Options& options) {
  const auto address = static_cast<std::uint8_t>(options.address);
  if (!codec::is_valve_address(address)) {
    std::fprintf(stderr, "gateway_latency: --address must be 0xD8..0xF7\n");
    return kExitFailure;
  }
  // Only frames for the bench valve: the gateway's frames to other (simulated) valves stay in
  // the kernel.
  const std::vector<can::Filter> bench_valve{{codec::to_valve_id(address), 0x1FFFFFFF}};
  auto started = InProcessGateway::start_if_asked(options);
  if (!started) return fail(started.error());
  const std::unique_ptr<InProcessGateway> in_process = std::move(*started);
  const std::unique_ptr<can::Bus> bus_owner =
      in_process ? in_process->endpoint(bench_valve)
                 : std::make_unique<can::SocketCanBus>(
                       options.can, can::SocketCanOptions{.filters = bench_valve});
  can::Bus& bus = *bus_owner;
  if (auto opened = bus.open(); !opened) return fail(opened.error());
  const Announcer announcer(bus, address, options.serial);

  // Listeners outlive the participant that calls them: declared first, destroyed last.
  std::atomic<bool> valve_online{false};
  OnSample<ValvePresence> presence([&](const ValvePresence& sample) {
    if (sample.serial() == options.serial) valve_online = sample.online();
  });
  // Position samples of the bench valve keyed by tenths of a degree, with the CAN receive time
  // the gateway put in received_ns.
  ArrivalLog<ValvePosition> positions(
      [&](const ValvePosition& sample) -> std::optional<std::int64_t> {
        if (sample.serial() != options.serial) return std::nullopt;
        return std::lround(sample.degrees() * 10.0F);
      },
      [](const ValvePosition& sample) { return sample.received_ns(); });
  // CommandStatus ACCEPTED keyed by command id. Its stamp_ns is the gateway's clock reading
  // when its reader handed the command over: it splits command -> frame into DDS delivery and
  // the gateway's own work (validate, encode, send).
  ArrivalLog<CommandStatus> accepted(
      [&](const CommandStatus& status) -> std::optional<std::int64_t> {
        if (status.serial() != options.serial || status.state() != COMMAND_ACCEPTED) {
          return std::nullopt;
        }
        return status.command_id();
      },
      [](const CommandStatus& status) { return status.stamp_ns(); });

  auto participant = dds::Participant::create(
      {.domain = options.domain, .profile_file = options.profile, .name = "gateway-latency-ecu"});
  if (!participant) return fail(participant.error());
  auto presence_reader =
      open_reader<ValvePresence>(**participant, topics::state_reader_qos(), &presence);
  if (!presence_reader) return fail(presence_reader.error());
  auto position_reader =
      open_reader<ValvePosition>(**participant, topics::state_reader_qos(), &positions);
  if (!position_reader) return fail(position_reader.error());
  auto status_reader =
      open_reader<CommandStatus>(**participant, topics::status_reader_qos(), &accepted);
  if (!status_reader) return fail(status_reader.error());
  auto command_writer = open_writer<ValveCommand>(**participant, topics::command_writer_qos());
  if (!command_writer) return fail(command_writer.error());

  if (!wait_until(
          [&] { return valve_online && matched(*command_writer) && matched(*position_reader); },
          kDiscoveryTimeout)) {
    std::fprintf(stderr,
                 "gateway_latency: no gateway on domain %d knows the bench valve after %lld s "
                 "(online %d, command writer matched %d, position reader matched %d)\n",
                 options.domain, static_cast<long long>(kDiscoveryTimeout.count()),
                 valve_online.load(), matched(*command_writer), matched(*position_reader));
    return kExitFailure;
  }

  // command -> frame: DataWriter::write(Stop) until the Stop frame's kernel receive stamp on
  // our socket.
  Series command_to_frame{"command_to_frame", {}, 0};
  std::map<std::int64_t, std::pair<std::int64_t, std::int64_t>> command_times;  // id: sent, frame
  ValveCommand command;
  command.serial(options.serial);
  command.origin("gateway-latency");
  command.kind(COMMAND_STOP);
  run_series(options, [&](int sequence, bool measured) {
    while (bus.receive(0ms)) {
      // Drop what came before t0 (poll requests, a late Stop) so it cannot be matched.
    }
    const auto id = static_cast<std::uint32_t>(sequence + 1);
    command.command_id(id);
    const std::int64_t sent = realtime_ns();
    (*command_writer)->write(&command);
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
      std::fprintf(stderr, "gateway_latency: Position not sent: %s\n",
                   written.error().reason.c_str());
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

}  // namespace teejet::bench
