// How many frames per second one SocketCanBus can send to another inside this kernel without
// loss. Not a test: run it inside user-mode-linux and read the table.
//
//   tests/uml/uml-run -- build-can/tests/uml/can/can_throughput [--interface vcan0]
//       [--frames 20000] [--rates 1000,2000,5000,0]   (0 = unpaced)
//       [--tick-ms 1] [--rcvbuf BYTES]   (receiving bus's receive_buffer_bytes; 0 = kernel's)
//
// For each rate: a sender paces N frames (woken once per tick, 1 ms by default) (sequence number in
// the data) through one bus; a receiver thread on a second bus (controller-side filters) reads
// them. Reported: frames received of sent, lost, the receiving bus's kernel drop counter, sends
// refused, and the CPU used.
#include <sys/resource.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "teejet/can/socketcan_bus.hpp"

namespace {

using namespace std::chrono_literals;
using SteadyClock = std::chrono::steady_clock;
using teejet::can::SocketCanBus;

double process_cpu_seconds() {
  rusage usage{};
  ::getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) / 1e6;
}

struct Result {
  std::uint64_t sent = 0, refused = 0, received = 0, out_of_order = 0, dropped = 0, retried = 0;
  double seconds = 0, cpu = 0;
};

Result run(const std::string& interface, std::uint64_t frames, double rate, double tick,
           int receive_buffer) {
  SocketCanBus tx(interface);
  SocketCanBus rx(interface, {.filters = teejet::can::controller_side_filters(),
                              .receive_buffer_bytes = receive_buffer});
  if (!tx.open() || !rx.open()) {
    std::fprintf(stderr, "cannot open %s\n", interface.c_str());
    std::exit(1);
  }
  Result result;
  std::atomic<bool> sending = true;
  std::thread receiver([&] {
    std::uint32_t expected = 0;
    for (;;) {
      auto got = rx.receive(300ms);
      if (!got) {
        if (!sending) break;  // idle 300 ms after the last send: everything is in
        continue;
      }
      std::uint32_t sequence;
      std::memcpy(&sequence, got->frame.data.data() + 1, sizeof sequence);
      if (sequence < expected) ++result.out_of_order;
      expected = sequence + 1;
      ++result.received;
    }
  });
  const double cpu_before = process_cpu_seconds();
  const auto start = SteadyClock::now();
  for (std::uint32_t i = 0; i < frames; ++i) {
    if (rate > 0) {
      // Wake at most once per tick and send every frame due by then: per-frame sleeps above
      // 1 kHz would measure the timer, not the bus.
      const double due = i / rate;
      const double wake = std::ceil(due / tick) * tick;
      const auto wake_at = start + std::chrono::duration_cast<SteadyClock::duration>(
                                       std::chrono::duration<double>(wake));
      if (SteadyClock::now() < wake_at) std::this_thread::sleep_until(wake_at);
    }
    teejet::codec::CanFrame frame{.id = 0x18EFD5D8, .dlc = 5};
    frame.data[0] = 0x02;
    std::memcpy(frame.data.data() + 1, &i, sizeof i);
    if (tx.send(frame)) {
      ++result.sent;
    } else {
      ++result.refused;
    }
  }
  const auto sent_at = SteadyClock::now();
  sending = false;
  receiver.join();
  result.seconds = std::chrono::duration<double>(sent_at - start).count();
  result.cpu = process_cpu_seconds() - cpu_before;
  result.dropped = rx.statistics().rx_dropped;
  result.retried = tx.statistics().tx_retried;
  return result;
}

}  // namespace

int main(int argc, char** argv) {
  std::string interface = "vcan0";
  std::uint64_t frames = 20000;
  double tick_ms = 1;
  int receive_buffer = teejet::can::SocketCanOptions{}.receive_buffer_bytes;
  std::vector<double> rates{1000, 2000, 5000, 10000, 20000, 0};
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string option = argv[i], value = argv[i + 1];
    if (option == "--interface") {
      interface = value;
    } else if (option == "--tick-ms") {
      tick_ms = std::stod(value);
    } else if (option == "--rcvbuf") {
      receive_buffer = std::stoi(value);
    } else if (option == "--frames") {
      frames = std::stoull(value);
    } else if (option == "--rates") {
      rates.clear();
      for (std::size_t at = 0; at < value.size();) {
        const std::size_t comma = std::min(value.find(',', at), value.size());
        rates.push_back(std::stod(value.substr(at, comma - at)));
        at = comma + 1;
      }
    } else {
      std::fprintf(stderr,
                   "usage: %s [--interface IF] [--frames N] [--rates R,R,...] [--tick-ms T] "
                   "[--rcvbuf BYTES]\n",
                   argv[0]);
      return 2;
    }
  }
  std::printf("%llu frames per rate on %s, receiving bus receive_buffer_bytes=%d\n",
              static_cast<unsigned long long>(frames), interface.c_str(), receive_buffer);
  std::printf("%10s %10s %8s %8s %8s %8s %8s %8s %8s\n", "target/s", "sent/s", "sent", "recv",
              "lost", "kdrop", "refused", "retried", "cpu%");
  for (const double rate : rates) {
    const Result r =
        run(interface, frames, rate, std::max(1 / rate, tick_ms / 1000), receive_buffer);
    std::printf("%10s %10.0f %8llu %8llu %8llu %8llu %8llu %8llu %8.0f\n",
                rate > 0 ? std::to_string(static_cast<long>(rate)).c_str() : "unpaced",
                static_cast<double>(r.sent) / r.seconds, static_cast<unsigned long long>(r.sent),
                static_cast<unsigned long long>(r.received),
                static_cast<unsigned long long>(r.sent - r.received),
                static_cast<unsigned long long>(r.dropped),
                static_cast<unsigned long long>(r.refused),
                static_cast<unsigned long long>(r.retried), 100 * r.cpu / r.seconds);
    if (r.out_of_order) std::printf("  %llu out of order!\n", (unsigned long long)r.out_of_order);
  }
}
