// SocketCAN (CAN_RAW) transport. See docs/can-transport.md for the design and the kernel
// behaviour it relies on (measured on Linux 6.1 in user-mode-linux).
//
// Threads: one thread sits in receive() while others call send() and statistics(). Everything
// shared lives in State under one mutex that is never held across poll(). The socket is held by
// shared_ptr so that a receiver polling it keeps the descriptor valid while another thread
// replaces or closes it; an eventfd wakes the receiver when that happens.
#include "teejet/can/socketcan_bus.hpp"

#include <linux/can.h>
#include <linux/can/raw.h>
#include <linux/errqueue.h>
#include <linux/net_tstamp.h>
#include <linux/sock_diag.h>
#include <net/if.h>
#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/eventfd.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <memory>

#include "error_frame.hpp"

namespace teejet::can {
namespace {

using SteadyClock = std::chrono::steady_clock;
using SteadyTime = SteadyClock::time_point;
using std::chrono::milliseconds;

constexpr std::size_t kBatch = 32;  // frames read per recvmmsg
// While the link is down, how often the interface flags are checked (SIOCGIFFLAGS) to notice
// that it is up again when no frame arrives to say so.
constexpr milliseconds kLinkCheckInterval{100};
// After ENOBUFS (device queue full) the queue is retried on a timer, not on POLLOUT: the socket
// stays writable while the qdisc refuses, so POLLOUT would spin.
constexpr milliseconds kRetryBackoffMin{2};
constexpr milliseconds kRetryBackoffMax{64};

std::string error_text(int error_number) { return std::strerror(error_number); }

bool is_vanished_error(int error_number) {
  return error_number == ENODEV || error_number == ENXIO || error_number == EBADF;
}

Timestamp realtime_now() {
  timespec now{};
  ::clock_gettime(CLOCK_REALTIME, &now);
  return std::chrono::seconds{now.tv_sec} + std::chrono::nanoseconds{now.tv_nsec};
}

Timestamp to_timestamp(const timespec& ts) {
  return std::chrono::seconds{ts.tv_sec} + std::chrono::nanoseconds{ts.tv_nsec};
}

// Kernel filter for one of ours: extended data frames only (11-bit and RTR never match).
can_filter kernel_filter(const Filter& filter) {
  return {(filter.id & CAN_EFF_MASK) | CAN_EFF_FLAG,
          (filter.mask & CAN_EFF_MASK) | CAN_EFF_FLAG | CAN_RTR_FLAG};
}

// A socket descriptor, closed when the last holder lets go.
class Socket {
 public:
  explicit Socket(int fd) : fd_(fd) {}
  ~Socket() { ::close(fd_); }
  Socket(const Socket&) = delete;
  Socket& operator=(const Socket&) = delete;
  int fd() const { return fd_; }

 private:
  int fd_;
};
using SocketPtr = std::shared_ptr<Socket>;

struct Opened {
  SocketPtr socket;
  int ifindex = 0;
};

// Creates, configures and binds a CAN_RAW socket. On failure, says why with errno.
Status open_socket(const std::string& interface, const SocketCanOptions& options, Opened& out) {
  const std::vector<Filter>& filters = options.filters;
  const int receive_buffer = options.receive_buffer_bytes;
  if (interface.empty() || interface.size() >= IFNAMSIZ) {
    return Status::failure("'" + interface + "' is not a network interface name", EINVAL);
  }
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) {
    const int error_number = errno;
    return Status::failure(interface + ": cannot create a CAN_RAW socket (" +
                               error_text(error_number) + "; is the can-raw module loaded?)",
                           error_number);
  }
  auto socket = std::make_shared<Socket>(fd);
  const auto fail = [&](const char* what) {
    const int error_number = errno;
    return Status::failure(interface + ": " + what + ": " + error_text(error_number), error_number);
  };

  std::vector<can_filter> kernel_filters;
  if (filters.empty()) {
    kernel_filters.push_back({CAN_EFF_FLAG, CAN_EFF_FLAG | CAN_RTR_FLAG});  // every EFF data frame
  } else {
    std::transform(filters.begin(), filters.end(), std::back_inserter(kernel_filters),
                   kernel_filter);
  }
  if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, kernel_filters.data(),
                   static_cast<socklen_t>(kernel_filters.size() * sizeof(can_filter))) < 0) {
    return fail("CAN_RAW_FILTER");
  }
  const can_err_mask_t error_mask = CAN_ERR_MASK;
  if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &error_mask, sizeof error_mask) < 0) {
    return fail("CAN_RAW_ERR_FILTER");
  }
  // Loopback stays on so that other sockets on this host (candump, a simulator) see our frames;
  // our own frames are not received back.
  const int on = 1, off = 0;
  if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_LOOPBACK, &on, sizeof on) < 0) {
    return fail("CAN_RAW_LOOPBACK");
  }
  if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, &off, sizeof off) < 0) {
    return fail("CAN_RAW_RECV_OWN_MSGS");
  }
  // Kernel receive time: SO_TIMESTAMPING software RX, else SO_TIMESTAMPNS. Without either, the
  // frame is stamped when read (both exist since long before any kernel we run on).
  const int stamping = SOF_TIMESTAMPING_RX_SOFTWARE | SOF_TIMESTAMPING_SOFTWARE;
  if (::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPING, &stamping, sizeof stamping) < 0) {
    (void)::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on);
  }
  if (::setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on) < 0) return fail("SO_RXQ_OVFL");
  if (receive_buffer > 0 &&
      ::setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &receive_buffer, sizeof receive_buffer) < 0 &&
      ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &receive_buffer, sizeof receive_buffer) < 0) {
    return fail("SO_RCVBUF");
  }

  const unsigned ifindex = ::if_nametoindex(interface.c_str());
  if (ifindex == 0) {
    const int error_number = errno == 0 ? ENODEV : errno;
    return Status::failure(interface + ": no such interface", error_number);
  }
  sockaddr_can address{};
  address.can_family = AF_CAN;
  address.can_ifindex = static_cast<int>(ifindex);
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) < 0) {
    return fail("bind");
  }
  out.socket = std::move(socket);
  out.ifindex = static_cast<int>(ifindex);
  return {};
}

// IFF_UP of the interface, asked through the socket: nullopt with errno when that fails.
std::optional<bool> interface_up(int fd, const std::string& interface) {
  ifreq request{};
  std::memcpy(request.ifr_name, interface.data(),
              std::min<std::size_t>(interface.size(), IFNAMSIZ - 1));
  if (::ioctl(fd, SIOCGIFFLAGS, &request) < 0) return std::nullopt;
  return (request.ifr_flags & IFF_UP) != 0;
}

can_frame to_kernel(const codec::CanFrame& frame) {
  can_frame out{};
  out.can_id = frame.extended ? (frame.id & CAN_EFF_MASK) | CAN_EFF_FLAG : frame.id & CAN_SFF_MASK;
  if (frame.remote) out.can_id |= CAN_RTR_FLAG;
  out.len = frame.dlc;
  std::copy_n(frame.data.begin(), frame.dlc, out.data);
  return out;
}

codec::CanFrame from_kernel(const can_frame& frame) {
  codec::CanFrame out;
  out.extended = (frame.can_id & CAN_EFF_FLAG) != 0;
  out.remote = (frame.can_id & CAN_RTR_FLAG) != 0;
  out.id = frame.can_id & (out.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
  out.dlc = std::min<std::uint8_t>(frame.len, codec::CanFrame::kMaxData);
  std::copy_n(frame.data, out.dlc, out.data.begin());
  return out;
}

// Difference of two readings of the kernel's 32-bit cumulative drop counter, 0 when `now` is
// older than `before` (the cmsg carries the count as of enqueueing, SO_MEMINFO the current one).
std::uint32_t drops_since(std::uint32_t before, std::uint32_t now) {
  const auto delta = static_cast<std::uint32_t>(now - before);
  return delta < 0x80000000U ? delta : 0;
}

// What one recvmmsg call brought, handed from the lock-free read to the locked bookkeeping.
struct ReadBatch {
  std::vector<TimedFrame> frames;
  std::vector<ErrorFrameReport> errors;
  std::optional<std::uint32_t> drop_counter;  // newest SO_RXQ_OVFL value seen
  int error_number = 0;                       // recvmmsg failed with this
};

ReadBatch read_batch(int fd) {
  struct Slot {
    can_frame frame;
    iovec vector;
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(scm_timestamping)) +
                                  CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(std::uint32_t))];
  };
  std::array<Slot, kBatch> slots;
  std::array<mmsghdr, kBatch> messages{};
  for (std::size_t i = 0; i < kBatch; ++i) {
    slots[i].vector = {&slots[i].frame, sizeof(can_frame)};
    messages[i].msg_hdr.msg_iov = &slots[i].vector;
    messages[i].msg_hdr.msg_iovlen = 1;
    messages[i].msg_hdr.msg_control = slots[i].control;
    messages[i].msg_hdr.msg_controllen = sizeof slots[i].control;
  }
  ReadBatch batch;
  const int count = ::recvmmsg(fd, messages.data(), kBatch, MSG_DONTWAIT, nullptr);
  if (count < 0) {
    batch.error_number = errno;
    return batch;
  }
  batch.frames.reserve(static_cast<std::size_t>(count));
  for (std::size_t i = 0; i < static_cast<std::size_t>(count); ++i) {
    msghdr& header = messages[i].msg_hdr;
    if (messages[i].msg_len != sizeof(can_frame) || (header.msg_flags & MSG_TRUNC)) continue;
    std::optional<Timestamp> stamp;
    for (cmsghdr* c = CMSG_FIRSTHDR(&header); c != nullptr; c = CMSG_NXTHDR(&header, c)) {
      if (c->cmsg_level != SOL_SOCKET) continue;
      if (c->cmsg_type == SCM_TIMESTAMPING) {
        scm_timestamping stamps;
        std::memcpy(&stamps, CMSG_DATA(c), sizeof stamps);
        if (stamps.ts[0].tv_sec != 0 || stamps.ts[0].tv_nsec != 0) {
          stamp = to_timestamp(stamps.ts[0]);  // [0]: software; [2] would be hardware
        }
      } else if (c->cmsg_type == SCM_TIMESTAMPNS) {
        timespec ts;
        std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
        stamp = to_timestamp(ts);
      } else if (c->cmsg_type == SO_RXQ_OVFL) {
        std::uint32_t drops;
        std::memcpy(&drops, CMSG_DATA(c), sizeof drops);
        batch.drop_counter = drops;
      }
    }
    const can_frame& frame = slots[i].frame;
    if (is_error_frame(frame.can_id)) {
      std::array<std::uint8_t, 8> data{};
      std::copy_n(frame.data, std::min<std::size_t>(frame.len, data.size()), data.begin());
      batch.errors.push_back(decode_error_frame(frame.can_id, data));
    } else {
      batch.frames.push_back({from_kernel(frame), stamp ? *stamp : realtime_now()});
    }
  }
  return batch;
}

}  // namespace

struct SocketCanBus::State {
  enum class Link : std::uint8_t {
    kClosed,
    kUp,
    kDown,  // ENETDOWN: the socket is kept, it works again when the link is back up
    kGone,  // ENODEV/ENXIO: the socket is closed, reopened with backoff
  };
  enum class WriteResult : std::uint8_t { kSent, kBusy, kFailed };

  State(const std::string& interface_name, const SocketCanOptions& bus_options)
      : name(interface_name), options(bus_options) {}

  const std::string& name;
  const SocketCanOptions& options;

  mutable std::mutex mutex;
  int wake_fd = -1;  // eventfd: wakes a receiver in poll()
  Link link = Link::kClosed;
  SocketPtr socket;
  int ifindex = 0;

  // The kernel's 32-bit cumulative drop counter of the current socket as last seen (SO_RXQ_OVFL
  // cmsg or SO_MEMINFO), and the total over every socket this bus has had.
  std::uint32_t socket_drop_counter = 0;
  std::uint64_t rx_dropped = 0;

  ControllerStatus controller;
  BusStatistics counters;  // frames_in/out, tx_failed, tx_retried, reopens

  std::deque<can_frame> retry;    // frames refused with ENOBUFS/EAGAIN, bounded
  bool retry_on_pollout = false;  // last refusal was EAGAIN (socket buffer): wait for POLLOUT
  SteadyTime retry_at{};
  milliseconds retry_backoff = kRetryBackoffMin;

  SteadyTime reopen_at{};
  milliseconds reopen_backoff{};
  SteadyTime link_check_at{};

  std::deque<TimedFrame> pending;  // read, not yet handed out

  // Everything below runs with `mutex` held.

  void wake() const {
    if (wake_fd < 0) return;
    const std::uint64_t one = 1;
    (void)!::write(wake_fd, &one, sizeof one);
  }

  // Frames waiting for retry cannot go out on a link that is down or gone: drop them visibly.
  std::size_t discard_retry() {
    const std::size_t count = retry.size();
    counters.tx_failed += count;
    retry.clear();
    retry_backoff = kRetryBackoffMin;
    retry_on_pollout = false;
    return count;
  }

  void note_drop_counter(std::uint32_t counter) {
    const std::uint32_t more = drops_since(socket_drop_counter, counter);
    socket_drop_counter += more;
    rx_dropped += more;
  }

  void refresh_drop_counter() {
    if (!socket) return;
    std::array<std::uint32_t, SK_MEMINFO_VARS> info{};
    socklen_t length = sizeof info;
    if (::getsockopt(socket->fd(), SOL_SOCKET, SO_MEMINFO, info.data(), &length) == 0 &&
        length >= (SK_MEMINFO_DROPS + 1) * sizeof(std::uint32_t)) {
      note_drop_counter(info[SK_MEMINFO_DROPS]);
    }
  }

  void retire_socket() {
    refresh_drop_counter();
    socket.reset();
    socket_drop_counter = 0;
  }

  void link_down(int error_number) {
    if (link != Link::kUp) return;
    link = Link::kDown;
    link_check_at = SteadyClock::now() + kLinkCheckInterval;
    const std::size_t dropped = discard_retry();
    spdlog::warn("{}: link down ({}); keeping the socket until it is up again{}", name,
                 error_text(error_number),
                 dropped ? fmt::format(", {} queued frame(s) dropped", dropped) : std::string());
  }

  void link_up() {
    if (link != Link::kDown) return;
    link = Link::kUp;
    spdlog::info("{}: link up again", name);
  }

  void vanished(int error_number) {
    if (link == Link::kGone || link == Link::kClosed) return;
    retire_socket();
    link = Link::kGone;
    reopen_backoff = options.reopen_backoff_min;
    reopen_at = SteadyClock::now() + reopen_backoff;
    const std::size_t dropped = discard_retry();
    spdlog::warn("{}: interface gone ({}); reopening with backoff {}..{} ms{}", name,
                 error_text(error_number), options.reopen_backoff_min.count(),
                 options.reopen_backoff_max.count(),
                 dropped ? fmt::format(", {} queued frame(s) dropped", dropped) : std::string());
    wake();
  }

  // Puts a freshly opened socket in place and learns whether its link is up.
  void adopt(Opened opened) {
    socket = std::move(opened.socket);
    ifindex = opened.ifindex;
    socket_drop_counter = 0;
    const auto up = interface_up(socket->fd(), name);
    link = up.value_or(true) ? Link::kUp : Link::kDown;
    link_check_at = SteadyClock::now() + kLinkCheckInterval;
  }

  // Reopens a vanished interface when its backoff is due. Cheap and non-blocking.
  void maybe_reopen(SteadyTime now) {
    if (link != Link::kGone || now < reopen_at) return;
    Opened opened;
    if (open_socket(name, options, opened)) {
      adopt(std::move(opened));
      ++counters.reopens;
      spdlog::info("{}: interface is back (ifindex {}); socket reopened{}", name, ifindex,
                   link == Link::kDown ? ", link still down" : "");
      wake();
      return;
    }
    reopen_backoff = std::min(reopen_backoff * 2, options.reopen_backoff_max);
    reopen_at = now + reopen_backoff;
  }

  // While the link is down and no frame says otherwise, ask the interface now and then.
  void check_link(SteadyTime now) {
    if (link != Link::kDown || now < link_check_at || !socket) return;
    link_check_at = now + kLinkCheckInterval;
    const auto up = interface_up(socket->fd(), name);
    if (!up) {
      const int error_number = errno;
      if (is_vanished_error(error_number)) vanished(error_number);
    } else if (*up) {
      link_up();
    }
  }

  // One non-blocking write; on failure, error_number says why and link faults are recorded.
  WriteResult write_frame(const can_frame& frame, int& error_number) {
    const ssize_t written = ::write(socket->fd(), &frame, sizeof frame);
    if (written == static_cast<ssize_t>(sizeof frame)) {
      ++counters.frames_out;
      link_up();
      return WriteResult::kSent;
    }
    error_number = written < 0 ? errno : EIO;
    if (error_number == ENOBUFS || error_number == EAGAIN) return WriteResult::kBusy;
    if (error_number == ENETDOWN) {
      link_down(error_number);
    } else if (is_vanished_error(error_number)) {
      vanished(error_number);
    }
    return WriteResult::kFailed;
  }

  void schedule_retry(int error_number, SteadyTime now) {
    retry_on_pollout = error_number == EAGAIN;
    retry_at = now + retry_backoff;
    retry_backoff = std::min(retry_backoff * 2, kRetryBackoffMax);
  }

  // Writes queued frames in order until the kernel refuses again.
  void flush_retry(SteadyTime now) {
    while (!retry.empty() && socket) {
      int error_number = 0;
      switch (write_frame(retry.front(), error_number)) {
        case WriteResult::kSent:
          retry.pop_front();
          ++counters.tx_retried;
          break;
        case WriteResult::kBusy:
          schedule_retry(error_number, now);
          return;
        case WriteResult::kFailed:
          if (!retry.empty()) {  // not a link fault (those empty the queue): drop this one
            retry.pop_front();
            ++counters.tx_failed;
          }
          break;
      }
    }
    if (retry.empty()) {
      retry_backoff = kRetryBackoffMin;
      retry_on_pollout = false;
    }
  }

  // Appends a refused frame to the bounded retry queue, or says why not.
  Status queue_for_retry(const can_frame& frame, int error_number) {
    if (retry.size() >= options.retry_queue_limit) {
      ++counters.tx_failed;
      return Status::failure(name + ": transmit queue full (" + error_text(error_number) +
                                 ") and the retry queue of " +
                                 std::to_string(options.retry_queue_limit) + " is full",
                             error_number);
    }
    const bool was_empty = retry.empty();
    retry.push_back(frame);
    if (was_empty) wake();  // the receiver adds the retry timer to its poll
    return {};
  }

  // Folds what one read brought into the bus.
  void absorb(ReadBatch& batch) {
    if (batch.drop_counter) note_drop_counter(*batch.drop_counter);
    for (const ErrorFrameReport& report : batch.errors) {
      if (apply(report, controller)) {
        spdlog::warn("{}: controller {} (tx errors {}, rx errors {}, problems 0x{:02x})", name,
                     to_string(controller.state), controller.tx_errors, controller.rx_errors,
                     controller.controller_problems);
      }
    }
    if (!batch.frames.empty() || !batch.errors.empty()) link_up();
    for (TimedFrame& frame : batch.frames) pending.push_back(std::move(frame));
    if (batch.error_number == ENETDOWN) {
      link_down(ENETDOWN);
    } else if (is_vanished_error(batch.error_number)) {
      vanished(batch.error_number);
    }
  }
};

SocketCanBus::SocketCanBus(std::string interface_name, SocketCanOptions options)
    : interface_(std::move(interface_name)),
      options_(std::move(options)),
      state_(std::make_unique<State>(interface_, options_)) {}

SocketCanBus::~SocketCanBus() {
  close();
  if (state_->wake_fd >= 0) ::close(state_->wake_fd);
}

// ---- the Bus interface ---------------------------------------------------------------------

Status SocketCanBus::open() {
  State& s = *state_;
  std::lock_guard lock(s.mutex);
  if (s.link != State::Link::kClosed) return {};
  if (s.wake_fd < 0) {
    s.wake_fd = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    if (s.wake_fd < 0) {
      const int error_number = errno;
      return Status::failure(interface_ + ": eventfd: " + error_text(error_number), error_number);
    }
  }
  Opened opened;
  if (Status status = open_socket(interface_, options_, opened); !status) return status;
  s.adopt(std::move(opened));
  spdlog::info("{}: SocketCAN open (ifindex {}, {} filter(s)){}", interface_, s.ifindex,
               options_.filters.size(), s.link == State::Link::kDown ? ", link is down" : "");
  return {};
}

void SocketCanBus::close() {
  State& s = *state_;
  std::lock_guard lock(s.mutex);
  if (s.link == State::Link::kClosed) return;
  s.retire_socket();
  s.discard_retry();
  s.pending.clear();
  s.link = State::Link::kClosed;
  s.wake();
  spdlog::info("{}: SocketCAN closed", interface_);
}

Status SocketCanBus::send(const codec::CanFrame& frame) {
  State& s = *state_;
  std::lock_guard lock(s.mutex);
  if (frame.dlc > codec::CanFrame::kMaxData ||
      frame.id > (frame.extended ? CAN_EFF_MASK : CAN_SFF_MASK)) {
    ++s.counters.tx_failed;
    return Status::failure(interface_ + ": not a valid classic CAN frame", EINVAL);
  }
  if (s.link == State::Link::kClosed) {
    return Status::failure(interface_ + ": bus is not open", EBADF);
  }
  // The clock is read only when there is something to time (a syscall in some kernels).
  const SteadyTime now =
      s.link == State::Link::kGone || !s.retry.empty() ? SteadyClock::now() : SteadyTime{};
  s.maybe_reopen(now);
  if (s.socket && !s.retry.empty()) s.flush_retry(now);
  if (!s.socket) {
    ++s.counters.tx_failed;
    return Status::failure(interface_ + ": interface is gone; reopening", ENODEV);
  }
  const can_frame kernel_frame = to_kernel(frame);
  if (!s.retry.empty()) return s.queue_for_retry(kernel_frame, ENOBUFS);  // keep the order
  int error_number = 0;
  switch (s.write_frame(kernel_frame, error_number)) {
    case State::WriteResult::kSent:
      return {};
    case State::WriteResult::kBusy:
      s.retry_backoff = kRetryBackoffMin;
      s.schedule_retry(error_number, SteadyClock::now());
      return s.queue_for_retry(kernel_frame, error_number);
    case State::WriteResult::kFailed:
      break;
  }
  ++s.counters.tx_failed;
  const char* what = error_number == ENETDOWN          ? ": link is down"
                     : is_vanished_error(error_number) ? ": interface is gone; reopening"
                                                       : ": write failed";
  return Status::failure(interface_ + what + " (" + error_text(error_number) + ")", error_number);
}

std::optional<TimedFrame> SocketCanBus::receive(std::chrono::milliseconds timeout) {
  State& s = *state_;
  const SteadyTime deadline = SteadyClock::now() + std::max(timeout, milliseconds{0});
  bool polled = false;
  for (;;) {
    SocketPtr socket;
    short events = POLLIN;
    SteadyTime wake_at = deadline;
    SteadyTime now;
    int wake_fd = -1;
    {
      std::lock_guard lock(s.mutex);
      if (s.link == State::Link::kClosed) return std::nullopt;
      if (!s.pending.empty()) {
        TimedFrame frame = std::move(s.pending.front());
        s.pending.pop_front();
        ++s.counters.frames_in;
        return frame;
      }
      now = SteadyClock::now();
      if (polled && now >= deadline) return std::nullopt;
      s.maybe_reopen(now);
      s.check_link(now);
      if (!s.retry.empty() && !s.retry_on_pollout && now >= s.retry_at) s.flush_retry(now);
      if (s.link == State::Link::kGone) wake_at = std::min(wake_at, s.reopen_at);
      if (s.link == State::Link::kDown) wake_at = std::min(wake_at, s.link_check_at);
      if (!s.retry.empty()) {
        if (s.retry_on_pollout) {
          events |= POLLOUT;
        } else {
          wake_at = std::min(wake_at, s.retry_at);
        }
      }
      socket = s.socket;
      wake_fd = s.wake_fd;
    }

    // Round up: a timeout truncated to 0 ms would spin through the last millisecond.
    const auto wait = std::max(wake_at - now, SteadyClock::duration{0});
    const int wait_ms = static_cast<int>(
        std::min<std::int64_t>(std::chrono::ceil<milliseconds>(wait).count(), 60'000));
    std::array<pollfd, 2> fds{{{wake_fd, POLLIN, 0}, {socket ? socket->fd() : -1, events, 0}}};
    const int ready = ::poll(fds.data(), fds.size(), wait_ms);
    polled = true;
    if (ready < 0) {
      if (errno == EINTR) continue;
      return std::nullopt;  // EINVAL/ENOMEM: nothing sensible to wait for
    }
    if (fds[0].revents & POLLIN) {
      std::uint64_t count;
      (void)!::read(wake_fd, &count, sizeof count);
    }
    if (!socket) continue;
    if (fds[1].revents & (POLLIN | POLLERR)) {
      ReadBatch batch = read_batch(socket->fd());
      std::lock_guard lock(s.mutex);
      if (socket == s.socket) s.absorb(batch);  // else replaced or closed meanwhile
    }
    if (fds[1].revents & POLLOUT) {
      std::lock_guard lock(s.mutex);
      if (socket == s.socket) s.flush_retry(SteadyClock::now());
    }
  }
}

BusStatistics SocketCanBus::statistics() const {
  State& s = *state_;
  std::lock_guard lock(s.mutex);
  s.refresh_drop_counter();
  BusStatistics out = s.counters;
  out.rx_dropped = s.rx_dropped;
  out.error_frames = s.controller.error_frames;
  out.state = (s.link == State::Link::kDown || s.link == State::Link::kGone) ? BusState::kDown
                                                                             : s.controller.state;
  out.tx_errors = s.controller.tx_errors;
  out.rx_errors = s.controller.rx_errors;
  out.controller_problems = s.controller.controller_problems;
  return out;
}

}  // namespace teejet::can
