#pragma once

// The CAN hardware abstraction: the whole contract a transport implements. The gateway, the
// simulator and the tools talk to this interface only; SocketCAN and the in-process virtual bus
// sit behind it.

#include <chrono>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "teejet/codec/frame.hpp"
#include "teejet/core/result.hpp"
#include "teejet/core/time.hpp"

namespace teejet::can {

struct TimedFrame {
  codec::CanFrame frame;
  Timestamp received{};  // wall clock: the kernel's receive time on SocketCAN, the bus clock's on
                         // the virtual bus
};

// Accepts an extended frame when (id & mask) == (filter.id & mask).
struct Filter {
  std::uint32_t id;
  std::uint32_t mask;
  bool matches(const codec::CanFrame& frame) const {
    return frame.extended && !frame.remote && (frame.id & mask) == (id & mask);
  }
};

// Valve to controller, 0x18EFD5xx: what a controller (the gateway) listens to.
std::vector<Filter> controller_side_filters();
// Controller to valve, 0x18EFxxD5: what a valve (the simulator) listens to.
std::vector<Filter> valve_side_filters();

// CAN controller error state, from error frames (SocketCAN) or set by a test (virtual bus).
enum class BusState : std::uint8_t {
  kErrorActive,
  kErrorWarning,
  kErrorPassive,
  kBusOff,
  kDown,  // the interface is down or gone; the bus keeps trying to recover
};

const char* to_string(BusState state);

struct BusStatistics {
  std::uint64_t frames_in = 0;     // frames delivered to the caller
  std::uint64_t frames_out = 0;    // frames handed to the bus
  std::uint64_t rx_dropped = 0;    // frames the kernel (or virtual queue) dropped before we read
  std::uint64_t tx_failed = 0;     // sends that failed visibly (link down, queue full, ...)
  std::uint64_t tx_retried = 0;    // sends that went out from the retry queue after ENOBUFS
  std::uint64_t error_frames = 0;  // error frames received
  std::uint64_t reopens = 0;       // times the socket was reopened after the interface vanished
  // Times the bus was cut off: its link went down or its controller went bus-off. A cut-off
  // shorter than the time between two looks at `state` still counts here.
  std::uint64_t outages = 0;
  BusState state = BusState::kErrorActive;
  std::uint16_t tx_errors = 0;            // controller transmit error counter
  std::uint16_t rx_errors = 0;            // controller receive error counter
  std::uint32_t controller_problems = 0;  // last CAN_ERR_CRTL_* bits seen (0 = none)
};

class Bus {
 public:
  virtual ~Bus() = default;

  // The interface ("vcan0") or virtual bus name.
  virtual const std::string& name() const = 0;

  // Opens the bus. A bus that cannot be opened stays closed and says why.
  virtual Status open() = 0;
  virtual void close() = 0;

  // Queues one frame for transmission without blocking. Fails visibly when the link is down or
  // the bounded retry queue is full; never buffers without bound.
  virtual Status send(const codec::CanFrame& frame) = 0;

  // Waits up to `timeout` for the next frame that passes the bus's filters. Link faults are
  // handled inside (waiting for the link, reopening a vanished interface); they show in
  // statistics(), never as a busy loop. Returns nullopt on timeout or when closed.
  virtual std::optional<TimedFrame> receive(std::chrono::milliseconds timeout) = 0;

  // Waits like receive() for the first frame, then appends to `out` every frame already waiting,
  // up to `max` in all: one wake-up and one lock for a burst instead of one per frame. Returns
  // how many were appended (0 on timeout or when closed). The default calls receive().
  virtual std::size_t receive_batch(std::vector<TimedFrame>& out, std::size_t max,
                                    std::chrono::milliseconds timeout);

  // Sends `frames` in order as send() would, stopping at the first that fails. The default
  // calls send(); the virtual bus hands a burst to each receiver at once.
  struct BatchSent {
    std::size_t sent = 0;
    Status status;  // the first failure, if any
  };
  virtual BatchSent send_batch(std::span<const codec::CanFrame> frames);

  virtual BusStatistics statistics() const = 0;
};

}  // namespace teejet::can
