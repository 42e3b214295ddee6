// SocketCAN on a real kernel: run inside user-mode-linux by ctest (tests/uml/uml-run), as root,
// with the CAN modules loaded. Each test makes its own vcan interface, so a test that breaks its
// link never disturbs the next one. Peers are what a user would use: cansend/candump, or a raw
// socket written here by hand. Waits are on conditions with deadlines, never sleep-and-hope;
// "nothing arrived" is proved by a marker frame sent after the frames that must not arrive.
// Where another thread or process must be ready first, the kernel says when it is: candump's
// filter shows in /proc/net/can, a receiver blocked in poll() shows as sleeping in /proc.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "support/eventually.hpp"
#include "teejet/can/socketcan_bus.hpp"

namespace teejet::can {
namespace {

using namespace std::chrono_literals;
using SteadyClock = std::chrono::steady_clock;
using teejet::testing::eventually;

// ---- helpers -----------------------------------------------------------------------------

int shell(const std::string& command) {
  const int status = std::system(("(" + command + ") >/dev/null 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

bool can_sockets_available() {
  const int fd = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (fd < 0) return false;
  ::close(fd);
  return true;
}

// CPU time (user + system) of the calling thread.
// A wait that spins costs about the whole wait in CPU; one that sleeps, a few ticks. The bound
// is half the wait, not a budget: in user-mode-linux on a loaded host getrusage charges whole
// 10 ms ticks to whatever runs, and an idle wait was charged 130 ms in 1 s (CI, load 6). The CPU
// figures are printed as measure lines for bench/run-test-timings.sh.
constexpr std::chrono::microseconds spinning_above(std::chrono::microseconds wait) {
  return wait / 2;
}

std::chrono::microseconds thread_cpu() {
  rusage usage{};
  ::getrusage(RUSAGE_THREAD, &usage);
  const auto to_us = [](const timeval& tv) {
    return std::chrono::seconds{tv.tv_sec} + std::chrono::microseconds{tv.tv_usec};
  };
  return to_us(usage.ru_utime) + to_us(usage.ru_stime);
}

Timestamp realtime_now() {
  return std::chrono::time_point_cast<Duration>(std::chrono::system_clock::now());
}

// Waits until the wall clock reads later than `time`. The kernel stamps a frame with the same
// clock while the sender's write() runs, so a frame written afterwards gets a later stamp than
// every frame written before `time` was read.
bool wall_clock_passes(Timestamp time) {
  const auto deadline = SteadyClock::now() + 1s;
  while (realtime_now() <= time) {
    if (SteadyClock::now() >= deadline) return false;
    std::this_thread::yield();
  }
  return true;
}

// True once some CAN_RAW socket on `interface` has a receive filter for `hex_id` (lower-case hex
// without flags) in the kernel: from then on such frames are queued for it. The kernel lists its
// receivers per list and device in /proc/net/can/rcvlist_*: "  DEVICE  CAN_ID  CAN_MASK ...".
bool receiver_registered(const std::string& interface, const std::string& hex_id) {
  for (const char* list : {"rcvlist_fil", "rcvlist_eff", "rcvlist_sff", "rcvlist_all"}) {
    std::ifstream file(std::string("/proc/net/can/") + list);
    for (std::string line; std::getline(file, line);) {
      std::istringstream fields(line);
      std::string device, can_id;
      if (fields >> device >> can_id && device == interface &&
          can_id.find(hex_id) != std::string::npos) {
        return true;
      }
    }
  }
  return false;
}

// The scheduler state of one of our threads, from /proc/self/task/TID/stat: 'R' running, 'S' in
// an interruptible wait (poll, a futex, a sleep), 0 when it cannot be read.
char thread_state(pid_t tid) {
  std::ifstream file("/proc/self/task/" + std::to_string(tid) + "/stat");
  std::string stat;
  std::getline(file, stat);
  const auto name_end = stat.rfind(')');  // the thread name may itself contain ") "
  return name_end != std::string::npos && name_end + 2 < stat.size() ? stat[name_end + 2] : '\0';
}

double ms(SteadyClock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); }

// A hand-written CAN_RAW peer: sends anything (11-bit, RTR, error frames), receives everything
// including error frames.
class RawPeer {
 public:
  // receive_buffer: SO_RCVBUFFORCE bytes (root), for a peer that must not drop; 0: default.
  explicit RawPeer(const std::string& interface, int receive_buffer = 0) {
    fd_ = ::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
    if (fd_ < 0) return;
    if (receive_buffer > 0) {
      ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUFFORCE, &receive_buffer, sizeof receive_buffer);
    }
    sockaddr_can address{};
    address.can_family = AF_CAN;
    address.can_ifindex = static_cast<int>(::if_nametoindex(interface.c_str()));
    if (::bind(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof address) < 0) {
      ::close(fd_);
      fd_ = -1;
    }
  }
  ~RawPeer() {
    if (fd_ >= 0) ::close(fd_);
  }
  RawPeer(const RawPeer&) = delete;
  RawPeer& operator=(const RawPeer&) = delete;

  bool ok() const { return fd_ >= 0; }

  // Sends a raw frame (flag bits in can_id); waits for buffer space rather than failing.
  bool send(canid_t can_id, std::vector<std::uint8_t> data = {}) {
    can_frame frame{};
    frame.can_id = can_id;
    frame.len = static_cast<std::uint8_t>(data.size());
    std::copy(data.begin(), data.end(), frame.data);
    for (int attempt = 0; attempt < 1000; ++attempt) {
      if (::write(fd_, &frame, sizeof frame) == static_cast<ssize_t>(sizeof frame)) return true;
      if (errno != EAGAIN && errno != ENOBUFS) return false;
      pollfd writable{fd_, POLLOUT, 0};
      ::poll(&writable, 1, 10);
    }
    return false;
  }

  std::optional<can_frame> receive(std::chrono::milliseconds timeout) {
    pollfd readable{fd_, POLLIN, 0};
    if (::poll(&readable, 1, static_cast<int>(timeout.count())) <= 0) return std::nullopt;
    can_frame frame{};
    if (::read(fd_, &frame, sizeof frame) != static_cast<ssize_t>(sizeof frame)) {
      return std::nullopt;
    }
    return frame;
  }

 private:
  int fd_ = -1;
};

constexpr canid_t eff(std::uint32_t id) { return id | CAN_EFF_FLAG; }

codec::CanFrame frame(std::uint32_t id, std::vector<std::uint8_t> data = {}) {
  codec::CanFrame out{.id = id, .dlc = static_cast<std::uint8_t>(data.size())};
  std::copy(data.begin(), data.end(), out.data.begin());
  return out;
}

// Receives until a frame with `id` arrives (or the deadline), returning every frame on the way.
std::vector<TimedFrame> receive_until(Bus& bus, std::uint32_t id,
                                      std::chrono::milliseconds within = 2s) {
  std::vector<TimedFrame> got;
  const auto deadline = SteadyClock::now() + within;
  while (SteadyClock::now() < deadline) {
    auto next = bus.receive(100ms);
    if (!next) continue;
    got.push_back(*next);
    if (next->frame.id == id) break;
  }
  return got;
}

// Waits until statistics() satisfy `condition`, receiving meanwhile so the bus sees the kernel.
template <typename Condition>
bool receive_until_stats(Bus& bus, Condition condition, std::chrono::milliseconds within = 2s) {
  const auto deadline = SteadyClock::now() + within;
  while (!condition(bus.statistics())) {
    if (SteadyClock::now() >= deadline) return false;
    (void)bus.receive(20ms);
  }
  return true;
}

// ---- fixture: a private vcan interface per test ---------------------------------------------

class SocketCanBench : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!can_sockets_available()) GTEST_SKIP() << "no SocketCAN here (run inside tests/uml)";
    if (::geteuid() != 0) GTEST_SKIP() << "needs root to create vcan interfaces";
    static int counter = 0;
    interface = "tjbench" + std::to_string(counter++);
    ASSERT_EQ(create_interface(), 0) << "cannot create " << interface;
  }
  void TearDown() override {
    if (!interface.empty()) (void)shell("ip link del " + interface);
  }

  int create_interface() {
    return shell("ip link add dev " + interface + " type vcan && ip link set " + interface + " up");
  }
  int link(const std::string& how) { return shell("ip link set " + interface + " " + how); }

  std::string interface;
};

// ---- filters, timestamps, loopback ------------------------------------------------------

TEST_F(SocketCanBench, ControllerSideReceivesOnlyValveToControllerFrames) {
  SocketCanBus bus(interface, {.filters = controller_side_filters()});
  ASSERT_TRUE(bus.open());
  // cansend: what a user would type. 8 hex digits = extended id.
  for (const char* line : {"18EFD5D8#020384",     // valve D8 -> controller: wanted
                           "18EFD8D5#00",         // controller -> valve D8: other direction
                           "18FEF1D8#0102",       // another PGN
                           "0D5#0203",            // 11-bit
                           "18EFD5D9#R",          // RTR with a matching id
                           "18EED5D8#01",         // PDU1 but another PF
                           "18EFD5E0#11223344"})  // valve E0 -> controller: wanted, the marker
  {
    ASSERT_EQ(shell(std::string("cansend ") + interface + " " + line), 0) << line;
  }
  const auto got = receive_until(bus, 0x18EFD5E0);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].frame, frame(0x18EFD5D8, {0x02, 0x03, 0x84}));
  EXPECT_EQ(got[1].frame, frame(0x18EFD5E0, {0x11, 0x22, 0x33, 0x44}));
  EXPECT_EQ(bus.statistics().frames_in, 2u);
}

TEST_F(SocketCanBench, ValveSideReceivesOnlyControllerToValveFrames) {
  SocketCanBus bus(interface, {.filters = valve_side_filters()});
  ASSERT_TRUE(bus.open());
  RawPeer peer(interface);
  ASSERT_TRUE(peer.ok());
  ASSERT_TRUE(peer.send(eff(0x18EFD5D8), {0x02}));         // valve -> controller
  ASSERT_TRUE(peer.send(eff(0x18EFD8D5), {0x11}));         // wanted
  ASSERT_TRUE(peer.send(eff(0x18EFD8D4), {0x11}));         // from another source
  ASSERT_TRUE(peer.send(0x0D5, {0x11}));                   // 11-bit
  ASSERT_TRUE(peer.send(eff(0x18EFD8D5) | CAN_RTR_FLAG));  // RTR
  ASSERT_TRUE(peer.send(eff(0x18FED8D5), {0x11}));         // another PGN
  ASSERT_TRUE(peer.send(eff(0x18EFE0D5), {0x00}));         // wanted, the marker
  const auto got = receive_until(bus, 0x18EFE0D5);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].frame, frame(0x18EFD8D5, {0x11}));
  EXPECT_EQ(got[1].frame, frame(0x18EFE0D5, {0x00}));
}

TEST_F(SocketCanBench, NoFiltersMeansEveryExtendedDataFrame) {
  SocketCanBus bus(interface);
  ASSERT_TRUE(bus.open());
  RawPeer peer(interface);
  ASSERT_TRUE(peer.ok());
  ASSERT_TRUE(peer.send(eff(0x18FEF100), {1}));
  ASSERT_TRUE(peer.send(0x123, {2}));                      // 11-bit: never
  ASSERT_TRUE(peer.send(eff(0x18FEF100) | CAN_RTR_FLAG));  // RTR: never
  ASSERT_TRUE(peer.send(eff(0x00000001), {3}));
  const auto got = receive_until(bus, 0x00000001);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].frame, frame(0x18FEF100, {1}));
  EXPECT_EQ(got[1].frame, frame(0x00000001, {3}));
}

TEST_F(SocketCanBench, FramesCarryKernelTimestampsCloseToTheClockAndInOrder) {
  SocketCanBus bus(interface, {.filters = controller_side_filters()});
  ASSERT_TRUE(bus.open());
  RawPeer peer(interface);
  ASSERT_TRUE(peer.ok());
  const Timestamp before = realtime_now();
  constexpr int kFrames = 50;
  for (int i = 0; i < kFrames; ++i) {
    ASSERT_TRUE(peer.send(eff(0x18EFD5D8), {0x11, static_cast<std::uint8_t>(i)}));
    // Every tenth frame, let the clock move on: the stamps must then differ, whatever the clock's
    // resolution, so equal stamps cannot pass for real ones.
    if (i % 10 == 9) {
      ASSERT_TRUE(wall_clock_passes(realtime_now()));
    }
  }
  std::vector<TimedFrame> got;
  while (got.size() < kFrames) {
    auto next = bus.receive(2s);
    ASSERT_TRUE(next) << "after " << got.size() << " frames";
    got.push_back(*next);
  }
  const Timestamp after = realtime_now();
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].frame.data[1], i);
    EXPECT_GE(got[i].received, before) << i;
    EXPECT_LE(got[i].received, after) << i;
    if (i > 0) {
      EXPECT_GE(got[i].received, got[i - 1].received) << i;
    }
  }
  EXPECT_GT(got.back().received, got.front().received);  // real stamps, not all the same
}

// A burst already in the kernel's queue leaves in batches (recvmmsg), in order, counted, each
// with its own stamp; `max` bounds a batch.
TEST_F(SocketCanBench, ReceiveBatchTakesABurstInOrderUpToMax) {
  SocketCanBus bus(interface, {.filters = controller_side_filters()});
  ASSERT_TRUE(bus.open());
  RawPeer peer(interface);
  ASSERT_TRUE(peer.ok());
  constexpr std::size_t kFrames = 100;
  for (std::size_t i = 0; i < kFrames; ++i) {
    ASSERT_TRUE(peer.send(eff(0x18EFD5D8), {0x02, static_cast<std::uint8_t>(i)}));
  }
  std::vector<TimedFrame> got;
  std::size_t batches = 0;
  const auto deadline = SteadyClock::now() + 5s;
  while (got.size() < kFrames && SteadyClock::now() < deadline) {
    const std::size_t before = got.size();
    const std::size_t taken = bus.receive_batch(got, 40, 1s);
    EXPECT_EQ(got.size(), before + taken);
    EXPECT_LE(taken, 40u);
    if (taken > 0) ++batches;
  }
  ASSERT_EQ(got.size(), kFrames);
  for (std::size_t i = 0; i < kFrames; ++i) EXPECT_EQ(got[i].frame.data[1], i) << i;
  EXPECT_LT(batches, kFrames / 4) << "the burst left one frame at a time";
  EXPECT_EQ(bus.statistics().frames_in, kFrames);
  std::vector<TimedFrame> none;
  EXPECT_EQ(bus.receive_batch(none, 40, 0ms), 0u);
}

TEST_F(SocketCanBench, OwnFramesAreNotReceivedBackButOtherSocketsSeeThem) {
  SocketCanBus bus(interface);  // no filters: our own 0x18EFD8D5 would pass them
  ASSERT_TRUE(bus.open());
  RawPeer peer(interface);
  ASSERT_TRUE(peer.ok());
  ASSERT_TRUE(bus.send(frame(0x18EFD8D5, {0x00})));
  auto seen = peer.receive(2s);
  ASSERT_TRUE(seen);
  EXPECT_EQ(seen->can_id, eff(0x18EFD8D5));
  ASSERT_TRUE(peer.send(eff(0x18EFD5D8), {0x77}));  // marker, after our own frame
  auto first = bus.receive(2s);
  ASSERT_TRUE(first);
  EXPECT_EQ(first->frame, frame(0x18EFD5D8, {0x77}));

  // candump, an independent process, sees what the bus sends. One frame, sent once candump's
  // filter is in the kernel: it must print exactly that frame and exit by itself.
  std::FILE* candump =
      ::popen(("timeout 5 candump -L -n 1 " + interface + ",18EFD9D5:1FFFFFFF").c_str(), "r");
  ASSERT_NE(candump, nullptr);
  const bool listening = eventually([&] { return receiver_registered(interface, "18efd9d5"); }, 4s);
  const bool sent = listening && bus.send(frame(0x18EFD9D5, {0x11, 0x22})).ok();
  std::string line(256, '\0');
  // Returns once candump printed its frame, or at the latest when `timeout` ends it.
  if (std::fgets(line.data(), static_cast<int>(line.size()), candump) == nullptr) line.clear();
  const int status = ::pclose(candump);
  ASSERT_TRUE(listening) << "candump's filter never showed in /proc/net/can";
  ASSERT_TRUE(sent);
  EXPECT_NE(line.find(interface + " 18EFD9D5#1122"), std::string::npos) << line;
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "candump: status " << status;
}

// ---- link faults ---------------------------------------------------------------------------

TEST_F(SocketCanBench, LinkDownFailsSendsVisiblyIdlesQuietlyAndRecoversWhenUp) {
  SocketCanBus bus(interface, {.filters = controller_side_filters()});
  ASSERT_TRUE(bus.open());
  ASSERT_EQ(link("down"), 0);

  const Status refused = bus.send(frame(0x18EFD8D5, {0x11}));
  EXPECT_FALSE(refused);
  EXPECT_EQ(refused.error().os_error, ENETDOWN) << refused.error().reason;
  EXPECT_EQ(bus.statistics().state, BusState::kDown);
  EXPECT_EQ(bus.statistics().tx_failed, 1u);

  const auto cpu_before = thread_cpu();
  const auto started = SteadyClock::now();
  EXPECT_FALSE(bus.receive(1s));
  const auto waited = SteadyClock::now() - started;
  const auto cpu = thread_cpu() - cpu_before;
  EXPECT_GE(waited, 1s);
  EXPECT_LT(cpu, spinning_above(1s)) << "spinning while the link is down";
  EXPECT_EQ(bus.statistics().state, BusState::kDown);

  ASSERT_EQ(link("up"), 0);
  const auto up_at = SteadyClock::now();
  RawPeer peer(interface);
  ASSERT_TRUE(peer.ok());
  std::optional<TimedFrame> got;
  while (!got && SteadyClock::now() - up_at < 2s) {
    ASSERT_TRUE(peer.send(eff(0x18EFD5D8), {0x02}));
    got = bus.receive(20ms);
  }
  const auto recovery = SteadyClock::now() - up_at;
  ASSERT_TRUE(got);
  EXPECT_TRUE(bus.send(frame(0x18EFD8D5, {0x11})));
  EXPECT_EQ(bus.statistics().state, BusState::kErrorActive);
  EXPECT_EQ(bus.statistics().reopens, 0u);  // same socket
  std::cout << "[ measure  ] link down: receive(1 s) used " << cpu.count() << " us CPU; "
            << "frames again " << ms(recovery) << " ms after 'ip link set up'\n";
}

TEST_F(SocketCanBench, DeletedInterfaceIsReopenedWhenItReturns) {
  SocketCanBus bus(interface, {.filters = controller_side_filters()});
  ASSERT_TRUE(bus.open());
  ASSERT_EQ(shell("ip link del " + interface), 0);
  ASSERT_TRUE(
      receive_until_stats(bus, [](const BusStatistics& s) { return s.state == BusState::kDown; }));
  const Status refused = bus.send(frame(0x18EFD8D5, {0x11}));
  EXPECT_FALSE(refused);
  EXPECT_TRUE(refused.error().os_error == ENODEV || refused.error().os_error == ENXIO)
      << refused.error().reason;

  const auto cpu_before = thread_cpu();
  EXPECT_FALSE(bus.receive(1s));  // reopen attempts with backoff meanwhile, all failing
  const auto cpu = thread_cpu() - cpu_before;
  EXPECT_LT(cpu, spinning_above(1s)) << "spinning while the interface is gone";
  EXPECT_EQ(bus.statistics().reopens, 0u);

  ASSERT_EQ(create_interface(), 0);
  const auto back_at = SteadyClock::now();
  RawPeer peer(interface);
  ASSERT_TRUE(peer.ok());
  std::optional<TimedFrame> got;
  while (!got && SteadyClock::now() - back_at < 3s) {
    ASSERT_TRUE(peer.send(eff(0x18EFD5D8), {0x02}));
    got = bus.receive(20ms);
  }
  const auto recovery = SteadyClock::now() - back_at;
  ASSERT_TRUE(got);
  const auto stats = bus.statistics();
  EXPECT_EQ(stats.reopens, 1u);
  EXPECT_EQ(stats.state, BusState::kErrorActive);
  EXPECT_TRUE(bus.send(frame(0x18EFD8D5, {0x11})));
  auto seen = peer.receive(2s);
  ASSERT_TRUE(seen);
  EXPECT_EQ(seen->can_id, eff(0x18EFD8D5));
  std::cout << "[ measure  ] interface gone: receive(1 s) used " << cpu.count() << " us CPU; "
            << "frames again " << ms(recovery) << " ms after re-creating it\n";
}

TEST_F(SocketCanBench, SendAloneNoticesAndRecoversADeletedInterface) {
  // A bus nobody receives on still reopens: send() attempts the reopen when its backoff is due.
  SocketCanBus bus(interface);
  ASSERT_TRUE(bus.open());
  ASSERT_EQ(shell("ip link del " + interface), 0);
  const Status refused = bus.send(frame(0x18EFD8D5, {0x11}));
  EXPECT_FALSE(refused);
  EXPECT_EQ(refused.error().os_error, ENXIO) << refused.error().reason;
  EXPECT_EQ(bus.statistics().state, BusState::kDown);
  ASSERT_EQ(create_interface(), 0);
  RawPeer peer(interface);
  ASSERT_TRUE(peer.ok());
  // Each refused send tries the reopen once its backoff is due; the first accepted one is seen.
  ASSERT_TRUE(eventually([&] { return bus.send(frame(0x18EFD8D5, {0x22})).ok(); }, 2s));
  auto seen = peer.receive(1s);
  ASSERT_TRUE(seen);
  EXPECT_EQ(seen->data[0], 0x22);
  EXPECT_EQ(bus.statistics().reopens, 1u);
}

TEST_F(SocketCanBench, OpenFailsVisiblyForAMissingInterface) {
  SocketCanBus bus("tjbench-none");  // the default: no waiting
  const Status status = bus.open();
  ASSERT_FALSE(status);
  EXPECT_EQ(status.error().os_error, ENODEV) << status.error().reason;
  EXPECT_EQ(status.error().reason, "tjbench-none: no such interface");
  EXPECT_FALSE(bus.send(frame(0x18EFD8D5, {0x11})));
  EXPECT_FALSE(bus.receive(0ms));
}

TEST_F(SocketCanBench, WaitsForAMissingInterfaceAndUsesItOnceCreated) {
  const std::string late = interface + "l";
  SocketCanBus bus(late, {.filters = controller_side_filters(), .wait_for_interface = true});
  ASSERT_TRUE(bus.open());
  EXPECT_EQ(bus.statistics().state, BusState::kDown);
  const Status refused = bus.send(frame(0x18EFD8D5, {0x11}));
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().os_error, ENODEV) << refused.error().reason;
  // Waiting costs nothing while the backoff has grown to its maximum.
  const auto cpu_before = thread_cpu();
  EXPECT_FALSE(bus.receive(1s));
  const auto cpu = thread_cpu() - cpu_before;
  EXPECT_LT(cpu, spinning_above(1s)) << "spinning while waiting for the interface";
  EXPECT_EQ(bus.statistics().reopens, 0u);

  ASSERT_EQ(shell("ip link add dev " + late + " type vcan && ip link set " + late + " up"), 0);
  const auto created_at = SteadyClock::now();
  RawPeer peer(late);
  ASSERT_TRUE(peer.ok());
  std::optional<TimedFrame> got;
  // The peer's frames reach the bus only once it has reopened: send until one is received.
  while (!got && SteadyClock::now() - created_at < 2s) {
    ASSERT_TRUE(peer.send(eff(0x18EFD5D8), {0x02}));
    got = bus.receive(20ms);
  }
  const auto waited = SteadyClock::now() - created_at;
  (void)shell("ip link del " + late);
  ASSERT_TRUE(got);  // the backoff's maximum is 500 ms: the time it took is printed below
  const auto stats = bus.statistics();
  EXPECT_EQ(stats.reopens, 1u);
  EXPECT_EQ(stats.state, BusState::kErrorActive);
  std::cout << "[ measure  ] missing at open: waiting 1 s used " << cpu.count()
            << " us CPU; frames " << ms(waited) << " ms after creating the interface\n";
}

TEST_F(SocketCanBench, NamesThatCanNeverWorkFailAtOpenEvenWhenWaiting) {
  SocketCanBus not_can("lo", {.wait_for_interface = true});
  const Status refused = not_can.open();
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().code, ErrorCode::kInvalidValue);
  EXPECT_EQ(refused.error().reason, "lo: not a CAN interface (bind: No such device)");

  SocketCanBus too_long("tjbench-sixteen!", {.wait_for_interface = true});  // IFNAMSIZ is 16
  const Status invalid = too_long.open();
  ASSERT_FALSE(invalid);
  EXPECT_EQ(invalid.error().reason, "'tjbench-sixteen!' is not a network interface name");
}

// ---- error frames, drops, retry queue ---------------------------------------------------------

TEST_F(SocketCanBench, ErrorFramesBecomeBusStateAndNeverData) {
  SocketCanBus bus(interface, {.filters = controller_side_filters()});
  ASSERT_TRUE(bus.open());
  RawPeer peer(interface);
  ASSERT_TRUE(peer.ok());
  std::uint8_t marker = 0;
  // Injects an error frame, then a data marker: once the marker is out, the error frame is in.
  const auto inject = [&](canid_t classes, std::vector<std::uint8_t> data) {
    data.resize(CAN_ERR_DLC);
    ASSERT_TRUE(peer.send(CAN_ERR_FLAG | classes, data));
    ASSERT_TRUE(peer.send(eff(0x18EFD5D8), {0x99, ++marker}));
    auto got = bus.receive(2s);
    ASSERT_TRUE(got);
    EXPECT_EQ(got->frame, frame(0x18EFD5D8, {0x99, marker}));  // the marker, not the error
  };

  inject(CAN_ERR_CRTL | CAN_ERR_CNT, {0, CAN_ERR_CRTL_TX_WARNING, 0, 0, 0, 0, 97, 5});
  auto stats = bus.statistics();
  EXPECT_EQ(stats.state, BusState::kErrorWarning);
  EXPECT_EQ(stats.tx_errors, 97);
  EXPECT_EQ(stats.rx_errors, 5);
  EXPECT_EQ(stats.controller_problems, CAN_ERR_CRTL_TX_WARNING);

  inject(CAN_ERR_CRTL | CAN_ERR_CNT, {0, CAN_ERR_CRTL_TX_PASSIVE, 0, 0, 0, 0, 135, 5});
  stats = bus.statistics();
  EXPECT_EQ(stats.state, BusState::kErrorPassive);
  EXPECT_EQ(stats.tx_errors, 135);

  inject(CAN_ERR_PROT | CAN_ERR_BUSERROR, {0, 0, CAN_ERR_PROT_BIT, CAN_ERR_PROT_LOC_ACK});
  EXPECT_EQ(bus.statistics().state, BusState::kErrorPassive);  // a bus error changes no state

  inject(CAN_ERR_BUSOFF, {});
  EXPECT_EQ(bus.statistics().state, BusState::kBusOff);

  inject(CAN_ERR_RESTARTED, {});
  stats = bus.statistics();
  EXPECT_EQ(stats.state, BusState::kErrorActive);
  EXPECT_EQ(stats.tx_errors, 0);
  EXPECT_EQ(stats.rx_errors, 0);
  EXPECT_EQ(stats.controller_problems, 0u);
  EXPECT_EQ(stats.error_frames, 5u);
  EXPECT_EQ(stats.frames_in, 5u);  // the markers only
}

TEST_F(SocketCanBench, BusOffRefusesSendsUntilTheControllerRestarts) {
  SocketCanBus bus(interface, {.filters = controller_side_filters()});
  ASSERT_TRUE(bus.open());
  RawPeer peer(interface);
  ASSERT_TRUE(peer.ok());
  const auto inject = [&](canid_t classes, std::vector<std::uint8_t> data, BusState expected) {
    data.resize(CAN_ERR_DLC);
    ASSERT_TRUE(peer.send(CAN_ERR_FLAG | classes, data));
    ASSERT_TRUE(
        receive_until_stats(bus, [&](const BusStatistics& s) { return s.state == expected; }));
  };
  // Error-passive still transmits: the frame goes out.
  inject(CAN_ERR_CRTL | CAN_ERR_CNT, {0, CAN_ERR_CRTL_TX_PASSIVE, 0, 0, 0, 0, 130, 0},
         BusState::kErrorPassive);
  EXPECT_TRUE(bus.send(frame(0x18EFD8D5, {0x01})));
  const auto seen = [](RawPeer& on) -> int {
    auto got = on.receive(1s);
    return got ? got->data[0] : -1;
  };
  EXPECT_EQ(seen(peer), 0x01);

  inject(CAN_ERR_BUSOFF, {}, BusState::kBusOff);
  const Status refused = bus.send(frame(0x18EFD8D5, {0x02}));
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().reason,
            interface + ": controller is bus-off; nothing is sent until it restarts");

  inject(CAN_ERR_RESTARTED, {}, BusState::kErrorActive);
  EXPECT_TRUE(bus.send(frame(0x18EFD8D5, {0x03})));
  EXPECT_EQ(seen(peer), 0x03);  // not 0x02: the refused frame never went out

  // Taking the link down and up is the other way a controller leaves bus-off.
  inject(CAN_ERR_BUSOFF, {}, BusState::kBusOff);
  ASSERT_EQ(link("down"), 0);
  ASSERT_TRUE(
      receive_until_stats(bus, [](const BusStatistics& s) { return s.state == BusState::kDown; }));
  ASSERT_EQ(link("up"), 0);
  ASSERT_TRUE(receive_until_stats(
      bus, [](const BusStatistics& s) { return s.state == BusState::kErrorActive; }));
  RawPeer after_restart(interface);  // the old peer's next read reports the link going down
  ASSERT_TRUE(after_restart.ok());
  EXPECT_TRUE(bus.send(frame(0x18EFD8D5, {0x04})));
  EXPECT_EQ(seen(after_restart), 0x04);
  EXPECT_EQ(bus.statistics().tx_failed, 1u);
}

TEST_F(SocketCanBench, KernelDropsAreCountedAndAccumulateAcrossReopens) {
  SocketCanBus bus(interface, {.filters = controller_side_filters(),
                               .receive_buffer_bytes = 0});  // the kernel default: ~280 frames
  ASSERT_TRUE(bus.open());
  constexpr std::uint64_t kFlood = 2000;  // far more than that buffer holds
  std::uint64_t sent = 0;
  const auto flood_and_drain = [&] {
    RawPeer peer(interface);
    ASSERT_TRUE(peer.ok());
    for (std::uint64_t i = 0; i < kFlood; ++i) {
      ASSERT_TRUE(peer.send(eff(0x18EFD5D8), {0x02, 0, 0}));
    }
    sent += kFlood;
    EXPECT_GT(bus.statistics().rx_dropped, 0u);  // known before anything is read (SO_MEMINFO)
    while (bus.receive(300ms)) {
    }
  };
  flood_and_drain();
  auto stats = bus.statistics();
  const std::uint64_t first_drops = stats.rx_dropped;
  EXPECT_GT(first_drops, 0u);
  EXPECT_EQ(stats.frames_in + stats.rx_dropped, sent);
  std::cout << "[ measure  ] flood of " << kFlood << " unread: " << stats.frames_in << " queued, "
            << stats.rx_dropped << " dropped by the kernel\n";

  // A new socket starts its kernel counter at 0: the bus keeps the total.
  ASSERT_EQ(shell("ip link del " + interface), 0);
  ASSERT_TRUE(
      receive_until_stats(bus, [](const BusStatistics& s) { return s.state == BusState::kDown; }));
  ASSERT_EQ(create_interface(), 0);
  ASSERT_TRUE(receive_until_stats(bus, [](const BusStatistics& s) { return s.reopens == 1; }));
  flood_and_drain();
  stats = bus.statistics();
  EXPECT_GT(stats.rx_dropped, first_drops);
  EXPECT_EQ(stats.frames_in + stats.rx_dropped, sent);
}

TEST_F(SocketCanBench, TheDefaultReceiveBufferAbsorbsTheSameFlood) {
  SocketCanBus bus(interface, {.filters = controller_side_filters()});  // 1 MiB (RCVBUFFORCE)
  ASSERT_TRUE(bus.open());
  RawPeer peer(interface);
  ASSERT_TRUE(peer.ok());
  for (int i = 0; i < 2000; ++i) ASSERT_TRUE(peer.send(eff(0x18EFD5D8), {0x02, 0, 0}));
  while (bus.receive(300ms)) {
  }
  const auto stats = bus.statistics();
  EXPECT_EQ(stats.rx_dropped, 0u);
  EXPECT_EQ(stats.frames_in, 2000u);
}

TEST_F(SocketCanBench, FullDeviceQueueUsesTheBoundedRetryQueue) {
  // sch_plug holds frames until released: a device queue that is full, so the kernel answers
  // ENOBUFS, exactly as a real CAN controller's full queue does.
  if (shell("modprobe sch_plug || insmod /usr/lib/uml/modules/$(uname -r)/kernel/net/sched/"
            "sch_plug.ko || lsmod | grep -q sch_plug") != 0) {
    GTEST_SKIP() << "no sch_plug qdisc";
  }
  ASSERT_EQ(shell("tc qdisc add dev " + interface + " root plug limit 64"), 0);  // 4 frames
  constexpr std::size_t kRetryLimit = 6;
  SocketCanBus bus(interface, {.retry_queue_limit = kRetryLimit});
  ASSERT_TRUE(bus.open());
  RawPeer peer(interface);
  ASSERT_TRUE(peer.ok());

  std::uint8_t sequence = 0;
  for (std::size_t i = 0; i < 4 + kRetryLimit; ++i) {
    ASSERT_TRUE(bus.send(frame(0x18EFD8D5, {0x05, sequence++}))) << i;  // plugged, then queued
  }
  const Status refused = bus.send(frame(0x18EFD8D5, {0x05, 0xFF}));
  EXPECT_FALSE(refused);
  EXPECT_EQ(refused.error().os_error, ENOBUFS) << refused.error().reason;
  auto stats = bus.statistics();
  EXPECT_EQ(stats.frames_out, 4u);
  EXPECT_EQ(stats.tx_failed, 1u);
  EXPECT_EQ(stats.tx_retried, 0u);

  // Idle while the queue is stuck: the retry timer backs off instead of spinning on POLLOUT.
  const auto cpu_before = thread_cpu();
  EXPECT_FALSE(bus.receive(500ms));
  const auto cpu = thread_cpu() - cpu_before;
  EXPECT_LT(cpu, spinning_above(500ms)) << "spinning on a stuck device queue";

  ASSERT_EQ(shell("tc qdisc change dev " + interface + " root plug release_indefinite"), 0);
  ASSERT_TRUE(receive_until_stats(
      bus, [&](const BusStatistics& s) { return s.tx_retried == kRetryLimit; }, 1s));
  stats = bus.statistics();
  EXPECT_EQ(stats.frames_out, 4 + kRetryLimit);
  EXPECT_EQ(stats.tx_failed, 1u);
  // Local sockets see each frame once it is accepted (plugged or not), in the order sent.
  for (std::uint8_t expected = 0; expected < sequence; ++expected) {
    auto seen = peer.receive(1s);
    ASSERT_TRUE(seen) << int{expected};
    EXPECT_EQ(seen->data[1], expected);
  }
  std::cout << "[ measure  ] retry queue stuck 500 ms: receive used " << cpu.count() << " us CPU\n";
}

// ---- idle and threads ------------------------------------------------------------------------

TEST_F(SocketCanBench, IdleReceiveSleeps) {
  SocketCanBus bus(interface, {.filters = controller_side_filters()});
  ASSERT_TRUE(bus.open());
  const auto cpu_before = thread_cpu();
  const auto started = SteadyClock::now();
  EXPECT_FALSE(bus.receive(2s));
  const auto waited = SteadyClock::now() - started;
  const auto cpu = thread_cpu() - cpu_before;
  EXPECT_GE(waited, 2s);
  EXPECT_LT(cpu, spinning_above(2s)) << "spinning while idle";
  std::cout << "[ measure  ] idle receive(2 s): " << ms(waited) << " ms, " << cpu.count()
            << " us CPU\n";
}

TEST_F(SocketCanBench, SendsFromOtherThreadsWhileOneThreadReceives) {
  SocketCanBus bus(interface);
  ASSERT_TRUE(bus.open());
  RawPeer peer(interface, 4 << 20);  // three unpaced senders on one guest CPU: room for all
  ASSERT_TRUE(peer.ok());
  constexpr int kPerThread = 200;
  std::atomic<int> received = 0;
  std::atomic<bool> stop = false;
  std::thread receiver([&] {
    while (!stop) {
      if (bus.receive(50ms)) ++received;
    }
  });
  std::atomic<int> seen = 0;  // by the peer, read concurrently so that its buffer never fills
  std::thread watcher([&] {
    while (seen < 3 * kPerThread) {
      auto next = peer.receive(2s);
      if (!next) break;
      if (next->can_id == eff(0x18EFD8D5)) ++seen;  // not the other peer's frames
    }
  });
  std::vector<std::thread> senders;
  for (std::uint8_t t = 0; t < 3; ++t) {
    senders.emplace_back([&bus, t] {
      for (int i = 0; i < kPerThread; ++i) {
        EXPECT_TRUE(bus.send(frame(0x18EFD8D5, {t, static_cast<std::uint8_t>(i)})));
      }
    });
  }
  RawPeer other(interface);
  ASSERT_TRUE(other.ok());
  for (int i = 0; i < kPerThread; ++i) ASSERT_TRUE(other.send(eff(0x18EFD5D8), {0x02}));
  for (auto& sender : senders) sender.join();
  watcher.join();
  (void)eventually([&] { return received >= kPerThread; }, 2s);  // checked exactly below
  stop = true;
  receiver.join();
  EXPECT_EQ(seen.load(), 3 * kPerThread);
  EXPECT_EQ(received.load(), kPerThread);
  const auto stats = bus.statistics();
  EXPECT_EQ(stats.frames_out, 3u * kPerThread);
  EXPECT_EQ(stats.frames_in, std::uint64_t{kPerThread});
  EXPECT_EQ(stats.rx_dropped, 0u);
}

TEST_F(SocketCanBench, CloseWakesABlockedReceiver) {
  SocketCanBus bus(interface);
  ASSERT_TRUE(bus.open());
  std::atomic<pid_t> receiver_tid = 0;
  std::optional<SteadyClock::time_point> returned_at;
  std::thread receiver([&] {
    receiver_tid = ::gettid();
    EXPECT_FALSE(bus.receive(40s));
    returned_at = SteadyClock::now();
  });
  // Close only once the receiver sleeps in receive()'s poll(), the one place this thread can
  // sleep: a close() before it waits would return it without testing the wake-up.
  const bool blocked = eventually(
      [&] {
        const pid_t tid = receiver_tid;
        return tid != 0 && thread_state(tid) == 'S';
      },
      5s);
  const auto closed_at = SteadyClock::now();
  bus.close();
  receiver.join();
  ASSERT_TRUE(blocked) << "the receiver never blocked";
  ASSERT_TRUE(returned_at);
  const auto woke_after = *returned_at - closed_at;
  // Ended by close(), not by its own 40 s: half of that tells them apart however loaded the
  // machine is; how soon is the figure printed below.
  EXPECT_LT(woke_after, 20s);
  EXPECT_FALSE(bus.send(frame(0x18EFD8D5, {0x11})));
  std::cout << "[ measure  ] close() woke the blocked receiver after " << ms(woke_after) << " ms\n";
}

}  // namespace
}  // namespace teejet::can
