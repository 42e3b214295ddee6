// SocketCAN (CAN_RAW) transport. See docs/can-transport.md for the design and the kernel
// behaviour it relies on (measured on Linux 6.1 in user-mode-linux).
//
// This file ties the parts together under one lock; each part does one job elsewhere:
// raw_socket (the socket and its system calls), kernel_frame (pure conversions), receive_batch
// (recvmmsg and its control messages), retry_queue (frames refused with ENOBUFS) and link_state
// (up, down, gone and the reopen backoff).
//
// Threads: one thread sits in receive() while others call send() and statistics(). Everything
// shared lives in State under one mutex that is never held across poll(). The socket is held by
// shared_ptr so that a receiver polling it keeps the descriptor valid while another thread
// replaces or closes it; an eventfd wakes the receiver when that happens.
#include "teejet/can/socketcan_bus.hpp"

#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <memory>

#include "error_frame.hpp"
#include "kernel_frame.hpp"
#include "link_state.hpp"
#include "raw_socket.hpp"
#include "receive_batch.hpp"
#include "retry_queue.hpp"

namespace teejet::can {
namespace {

using SteadyClock = std::chrono::steady_clock;
using std::chrono::milliseconds;
using Link = LinkState::State;

SteadyTime steady_now() { return SteadyClock::now(); }

std::string dropped_note(std::size_t dropped) {
  return dropped ? fmt::format(", {} queued frame(s) dropped", dropped) : std::string();
}

}  // namespace

struct SocketCanBus::State {
  State(const std::string& interface_name, const SocketCanOptions& bus_options)
      : name(interface_name),
        options(bus_options),
        link(bus_options.reopen_backoff_min, bus_options.reopen_backoff_max),
        retry(bus_options.retry_queue_limit) {}

  const std::string& name;
  const SocketCanOptions& options;

  mutable std::mutex mutex;
  int wake_fd = -1;  // eventfd: wakes a receiver in poll()
  LinkState link;
  SocketPtr socket;
  int ifindex = 0;

  DropCount drops;  // the kernel's drop counter, over every socket this bus has had
  ControllerStatus controller;
  BusStatistics counters;          // frames_in/out, tx_failed, tx_retried, reopens
  RetryQueue retry;                // frames refused with ENOBUFS/EAGAIN
  std::deque<TimedFrame> pending;  // read, not yet handed out

  // Everything below runs with `mutex` held.

  void wake() const {
    if (wake_fd < 0) return;
    const std::uint64_t one = 1;
    (void)!::write(wake_fd, &one, sizeof one);
  }

  // Frames waiting for retry cannot go out on a link that is down or gone: drop them visibly.
  std::size_t discard_retry() {
    const std::size_t count = retry.clear();
    counters.tx_failed += count;
    return count;
  }

  void refresh_drop_counter() {
    if (!socket) return;
    if (const auto counter = kernel_drop_counter(socket->fd())) drops.note(*counter);
  }

  void retire_socket() {
    refresh_drop_counter();
    socket.reset();
    drops.new_socket();
  }

  void link_down(int error_number) {
    if (!link.down(steady_now())) return;
    ++counters.outages;
    const std::size_t dropped = discard_retry();
    spdlog::warn("{}: link down ({}); keeping the socket until it is up again{}", name,
                 error_text(error_number), dropped_note(dropped));
  }

  void link_up() {
    if (!link.up()) return;
    spdlog::info("{}: link up again", name);
    controller_reset();
  }

  // Bringing an interface up (or a new one) restarts its controller: what error frames said
  // about the old one no longer holds, and a bus-off that ended this way sends no
  // CAN_ERR_RESTARTED.
  void controller_reset() {
    if (controller.state == BusState::kErrorActive) return;
    controller.state = BusState::kErrorActive;
    controller.tx_errors = 0;
    controller.rx_errors = 0;
    controller.controller_problems = 0;
    spdlog::info("{}: controller error-active again (link restarted)", name);
  }

  void vanished(int error_number) {
    if (link.state() == Link::kGone || link.state() == Link::kClosed) return;
    retire_socket();
    link.vanished(steady_now());
    const std::size_t dropped = discard_retry();
    spdlog::warn("{}: interface gone ({}); reopening with backoff {}..{} ms{}", name,
                 error_text(error_number), options.reopen_backoff_min.count(),
                 options.reopen_backoff_max.count(), dropped_note(dropped));
    wake();
  }

  // Puts a freshly opened socket in place and learns whether its link is up.
  void adopt(OpenedSocket opened) {
    socket = std::move(opened.socket);
    ifindex = opened.ifindex;
    drops.new_socket();
    const auto up = interface_up(socket->fd(), name);
    link.opened(up.value_or(true), steady_now());
    controller_reset();
  }

  // Reopens a vanished interface when its backoff is due. Cheap and non-blocking.
  void maybe_reopen(SteadyTime now) {
    if (!link.reopen_due(now)) return;
    Result<OpenedSocket> opened = open_socket(name, options);
    if (!opened) {
      link.reopen_failed(now);
      return;
    }
    adopt(std::move(opened).value());
    ++counters.reopens;
    spdlog::info("{}: interface is back (ifindex {}); socket reopened{}", name, ifindex,
                 link.state() == Link::kDown ? ", link still down" : "");
    wake();
  }

  // While the link is down and no frame says otherwise, ask the interface now and then.
  void check_link(SteadyTime now) {
    if (!link.check_due(now) || !socket) return;
    link.checked(now);
    const auto up = interface_up(socket->fd(), name);
    if (!up) {
      const int error_number = errno;
      if (is_vanished_error(error_number)) vanished(error_number);
    } else if (*up) {
      link_up();
    }
  }

  // One non-blocking write; on failure, error_number says why and link faults are recorded.
  WriteOutcome write(const can_frame& frame, int& error_number) {
    error_number = write_frame(socket->fd(), frame);
    if (error_number == 0) {
      ++counters.frames_out;
      link_up();
      return WriteOutcome::kSent;
    }
    if (error_number == ENOBUFS || error_number == EAGAIN) return WriteOutcome::kBusy;
    if (error_number == ENETDOWN) {
      link_down(error_number);
    } else if (is_vanished_error(error_number)) {
      vanished(error_number);
    }
    return WriteOutcome::kFailed;
  }

  // Writes queued frames in order until the kernel refuses again.
  void flush_retry(SteadyTime now) {
    if (!socket) return;
    const RetryQueue::Flushed flushed = retry.flush(
        now,
        [this](const can_frame& frame, int& error_number) { return write(frame, error_number); });
    counters.tx_retried += flushed.retried;
    counters.tx_failed += flushed.failed;
  }

  // Appends a refused frame to the bounded retry queue, or says why not.
  Status queue_for_retry(const can_frame& frame, int error_number) {
    const bool was_empty = retry.empty();
    if (!retry.push(frame)) {
      ++counters.tx_failed;
      std::string reason = name;
      reason += ": transmit queue full (" + error_text(error_number) + ") and the retry queue of ";
      reason += std::to_string(options.retry_queue_limit);
      reason += " is full";
      return Error{ErrorCode::kUnavailable, std::move(reason), error_number};
    }
    if (was_empty) wake();  // the receiver adds the retry timer to its poll
    return {};
  }

  // Folds what one read brought into the bus.
  void absorb(ReadBatch& batch) {
    if (batch.drop_counter) drops.note(*batch.drop_counter);
    for (const ErrorFrameReport& report : batch.errors) {
      if (apply(report, controller)) {
        if (controller.state == BusState::kBusOff) ++counters.outages;
        // Frames held for retry would go out long after their time once the controller is
        // back: a valve must not move to a target its commander has given up on.
        const std::size_t dropped =
            controller.state == BusState::kBusOff ? discard_retry() : std::size_t{0};
        spdlog::warn(
            "{}: controller {} (tx errors {}, rx errors {}, problems 0x{:02x}){}{}", name,
            to_string(controller.state), controller.tx_errors, controller.rx_errors,
            controller.controller_problems,
            controller.state == BusState::kBusOff ? "; refusing to send until it restarts" : "",
            dropped_note(dropped));
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
  if (s.link.state() != Link::kClosed) return {};
  if (s.wake_fd < 0) {
    s.wake_fd = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    if (s.wake_fd < 0) {
      const int error_number = errno;
      return Error{ErrorCode::kSystem, interface_ + ": eventfd: " + error_text(error_number),
                   error_number};
    }
  }
  Result<OpenedSocket> opened = open_socket(interface_, options_);
  if (!opened) {
    if (!options_.wait_for_interface || !is_missing_interface(opened.error())) {
      return opened.error();
    }
    s.link.missing(steady_now());
    spdlog::warn("{}: no such interface; waiting for it, retrying every {}..{} ms", interface_,
                 options_.reopen_backoff_min.count(), options_.reopen_backoff_max.count());
    return {};
  }
  s.adopt(std::move(opened).value());
  spdlog::info("{}: SocketCAN open (ifindex {}, {} filter(s)){}", interface_, s.ifindex,
               options_.filters.size(), s.link.state() == Link::kDown ? ", link is down" : "");
  return {};
}

void SocketCanBus::close() {
  State& s = *state_;
  std::lock_guard lock(s.mutex);
  if (s.link.state() == Link::kClosed) return;
  s.retire_socket();
  s.discard_retry();
  s.pending.clear();
  s.link.closed();
  s.wake();
  spdlog::info("{}: SocketCAN closed", interface_);
}

Status SocketCanBus::send(const codec::CanFrame& frame) {
  State& s = *state_;
  std::lock_guard lock(s.mutex);
  if (!is_classic_frame(frame)) {
    ++s.counters.tx_failed;
    return Error{ErrorCode::kInvalidValue, interface_ + ": not a valid classic CAN frame", EINVAL};
  }
  if (s.link.state() == Link::kClosed) {
    return Error{ErrorCode::kUnavailable, interface_ + ": bus is not open", EBADF};
  }
  // The clock is read only when there is something to time (a syscall in some kernels).
  const SteadyTime now =
      s.link.state() == Link::kGone || !s.retry.empty() ? steady_now() : SteadyTime{};
  s.maybe_reopen(now);
  if (!s.retry.empty()) s.flush_retry(now);
  if (!s.socket) {
    ++s.counters.tx_failed;
    return Error{ErrorCode::kUnavailable, interface_ + ": interface is gone; reopening", ENODEV};
  }
  if (s.controller.state == BusState::kBusOff) {
    ++s.counters.tx_failed;
    return Error{ErrorCode::kUnavailable,
                 interface_ + ": controller is bus-off; nothing is sent until it restarts",
                 ENETDOWN};
  }
  const can_frame kernel_frame = to_kernel(frame);
  if (!s.retry.empty()) return s.queue_for_retry(kernel_frame, ENOBUFS);  // keep the order
  int error_number = 0;
  switch (s.write(kernel_frame, error_number)) {
    case WriteOutcome::kSent:
      return {};
    case WriteOutcome::kBusy:
      s.retry.restart_backoff();
      s.retry.refused(error_number, steady_now());
      return s.queue_for_retry(kernel_frame, error_number);
    case WriteOutcome::kFailed:
      break;
  }
  ++s.counters.tx_failed;
  const char* what = error_number == ENETDOWN          ? ": link is down"
                     : is_vanished_error(error_number) ? ": interface is gone; reopening"
                                                       : ": write failed";
  std::string reason = interface_;
  reason += what;
  reason += " (" + error_text(error_number) + ")";
  return Error{ErrorCode::kSystem, std::move(reason), error_number};
}

std::optional<TimedFrame> SocketCanBus::receive(std::chrono::milliseconds timeout) {
  State& s = *state_;
  const SteadyTime deadline = steady_now() + std::max(timeout, milliseconds{0});
  bool polled = false;
  for (;;) {
    SocketPtr socket;
    short events = POLLIN;
    SteadyTime wake_at = deadline;
    SteadyTime now;
    int wake_fd = -1;
    {
      std::lock_guard lock(s.mutex);
      if (s.link.state() == Link::kClosed) return std::nullopt;
      if (!s.pending.empty()) {
        TimedFrame frame = std::move(s.pending.front());
        s.pending.pop_front();
        ++s.counters.frames_in;
        return frame;
      }
      now = steady_now();
      if (polled && now >= deadline) return std::nullopt;
      s.maybe_reopen(now);
      s.check_link(now);
      if (s.retry.due(now)) s.flush_retry(now);
      wake_at = s.link.next_wake(wake_at);
      if (s.retry.waits_for_pollout()) {
        events |= POLLOUT;
      } else if (!s.retry.empty()) {
        wake_at = std::min(wake_at, s.retry.retry_at());
      }
      socket = s.socket;
      wake_fd = s.wake_fd;
    }

    // Round up: a timeout truncated to 0 ms would spin through the last millisecond.
    const auto wait = std::max(wake_at - now, Duration{0});
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
      if (socket == s.socket) s.flush_retry(steady_now());
    }
  }
}

// recvmmsg already reads the kernel's queue in batches; the frames it read beyond the first
// leave together.
std::size_t SocketCanBus::receive_batch(std::vector<TimedFrame>& out, std::size_t max,
                                        std::chrono::milliseconds timeout) {
  if (max == 0) return 0;
  auto first = receive(timeout);
  if (!first) return 0;
  out.push_back(std::move(*first));
  std::size_t taken = 1;
  State& s = *state_;
  std::lock_guard lock(s.mutex);
  while (taken < max && !s.pending.empty()) {
    out.push_back(std::move(s.pending.front()));
    s.pending.pop_front();
    ++s.counters.frames_in;
    ++taken;
  }
  return taken;
}

BusStatistics SocketCanBus::statistics() const {
  State& s = *state_;
  std::lock_guard lock(s.mutex);
  s.refresh_drop_counter();
  BusStatistics out = s.counters;
  out.rx_dropped = s.drops.total;
  out.error_frames = s.controller.error_frames;
  out.state = s.link.faulty() ? BusState::kDown : s.controller.state;
  out.tx_errors = s.controller.tx_errors;
  out.rx_errors = s.controller.rx_errors;
  out.controller_problems = s.controller.controller_problems;
  return out;
}

}  // namespace teejet::can
