#pragma once

// The kernel's CAN structures and ours, converted both ways, and the arithmetic of the kernel's
// drop counter. Pure: no sockets, no system calls, no clock; unit-tested on the host with exact
// values (tests/can/kernel_frame_tests.cpp).

#include <linux/can.h>

#include <cstdint>
#include <ctime>
#include <vector>

#include "teejet/can/bus.hpp"

namespace teejet::can {

// True when `frame` is a classic CAN frame the kernel can carry: at most 8 data bytes and an id
// that fits its 29 (extended) or 11 bits. send() refuses anything else before converting.
bool is_classic_frame(const codec::CanFrame& frame);

// Our frame as the kernel writes it: CAN_EFF_FLAG on 29-bit ids, CAN_RTR_FLAG on remote
// requests, the id masked to its width, `dlc` data bytes (the rest zero). A dlc above 8 is
// clamped to 8 (send() has refused such a frame already; clamping keeps the copy in bounds).
can_frame to_kernel(const codec::CanFrame& frame);

// A data frame as the kernel read it. Flag bits become `extended`/`remote`; a length above 8
// (a malformed or CAN FD length) is clamped to 8 so the copy stays inside both buffers.
codec::CanFrame from_kernel(const can_frame& frame);

// The kernel filter for one of ours: extended data frames only, so 11-bit and RTR frames with a
// matching id never reach the process.
can_filter kernel_filter(const Filter& filter);

// The CAN_RAW_FILTER list for a bus: one entry per filter; none means every extended data frame.
std::vector<can_filter> kernel_filters(const std::vector<Filter>& filters);

// A kernel receive stamp (SCM_TIMESTAMPING, SCM_TIMESTAMPNS): wall clock since the Unix epoch.
Timestamp to_timestamp(const timespec& stamp);

// Difference of two readings of the kernel's 32-bit cumulative drop counter, across its
// wrap-around; 0 when `now` is older than `before` (the SO_RXQ_OVFL cmsg carries the count as of
// enqueueing, SO_MEMINFO the current one, so a later read can bring an older value).
std::uint32_t drops_since(std::uint32_t before, std::uint32_t now);

// The drop counter of the current socket as last seen, and the total over every socket the bus
// has had (a reopened socket starts counting at 0 again).
struct DropCount {
  std::uint32_t socket_counter = 0;
  std::uint64_t total = 0;

  // A reading of the current socket's counter: adds what is new since the last reading.
  void note(std::uint32_t counter) {
    const std::uint32_t more = drops_since(socket_counter, counter);
    socket_counter += more;
    total += more;
  }
  // Another socket from now on; the total stays.
  void new_socket() { socket_counter = 0; }
};

}  // namespace teejet::can
