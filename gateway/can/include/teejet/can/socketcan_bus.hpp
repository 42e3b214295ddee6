#pragma once

#include <chrono>
#include <cstddef>
#include <deque>
#include <mutex>

#include "teejet/can/bus.hpp"

namespace teejet::can {

struct SocketCanOptions {
  std::vector<Filter> filters;  // kernel filters (CAN_RAW_FILTER); empty: every extended frame
  std::size_t retry_queue_limit = 32;  // frames kept for retry after ENOBUFS; beyond: refused
  std::chrono::milliseconds reopen_backoff_min{100};  // after ENODEV, first reopen attempt
  std::chrono::milliseconds reopen_backoff_max{500};  // keeps recovery after re-creation < 1 s
  // Kernel receive buffer in bytes: SO_RCVBUFFORCE when allowed (CAP_NET_ADMIN), else SO_RCVBUF
  // (capped by net.core.rmem_max). 1 MiB holds ~1300 frames, over half a second of a saturated
  // 250 kbit/s bus; 0 keeps the kernel default (212992 bytes: ~280 frames).
  int receive_buffer_bytes = 1 << 20;
  // When the interface does not exist at open(): false fails open() (ENODEV); true opens the
  // bus in the gone state and retries with the reopen backoff, as for an interface deleted
  // later (a gateway started before its CAN driver is loaded). Names that can never work (too
  // long, an interface that is not CAN) and a refused socket() fail open() either way.
  bool wait_for_interface = false;
};

// CAN_RAW socket on a Linux SocketCAN interface (can0, vcan0). Kernel filters keep foreign
// frames out of the process, own frames are not received back, every frame carries the
// kernel's receive timestamp, error frames become BusState and error counters, and the kernel's
// drop counter (SO_RXQ_OVFL) shows as rx_dropped. Link faults are survived: after ENETDOWN the
// socket is kept and works again when the link comes back up; after ENODEV (interface deleted)
// it is closed and reopened with backoff until the interface returns. While the controller
// reports bus-off, send() refuses (nothing can go out) until it says it restarted.
class SocketCanBus final : public Bus {
 public:
  explicit SocketCanBus(std::string interface_name, SocketCanOptions options = {});
  ~SocketCanBus() override;
  SocketCanBus(const SocketCanBus&) = delete;
  SocketCanBus& operator=(const SocketCanBus&) = delete;

  const std::string& name() const override { return interface_; }
  Status open() override;
  void close() override;
  Status send(const codec::CanFrame& frame) override;
  std::optional<TimedFrame> receive(std::chrono::milliseconds timeout) override;
  std::size_t receive_batch(std::vector<TimedFrame>& out, std::size_t max,
                            std::chrono::milliseconds timeout) override;
  BusStatistics statistics() const override;

 private:
  const std::string interface_;
  const SocketCanOptions options_;
  // Implementation state (socket, retry queue, statistics) lives in the .cpp.
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace teejet::can
