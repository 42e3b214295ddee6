#pragma once

// A Bus that tells an observer about every frame that crosses it, in both directions, and is
// otherwise the bus it wraps: state, statistics, filters and errors are the inner bus's own.
// What a recorder of the raw bus (teejet-gateway --record-frames) stands on.

#include <memory>

#include "teejet/can/bus.hpp"

namespace teejet::can {

enum class FrameDirection : std::uint8_t {
  kReceived,  // taken off the bus by receive() or receive_batch()
  kSent,      // accepted by send() or send_batch()
};

// Called on the thread that sent or received the frame, while that thread waits: keep it cheap
// and never call back into the bus. Several threads may call it at once.
class FrameObserver {
 public:
  virtual ~FrameObserver() = default;
  // `stamp`: the frame's TimedFrame::received (the kernel's receive time on SocketCAN) for a
  // received frame; the wall clock when the bus accepted it for a sent one.
  virtual void on_frame(const codec::CanFrame& frame, FrameDirection direction,
                        Timestamp stamp) = 0;
};

class ObservedBus final : public Bus {
 public:
  // `observer` must outlive every send and receive made through this bus. `clock` stamps the
  // frames sent.
  ObservedBus(std::unique_ptr<Bus> inner, FrameObserver& observer,
              std::shared_ptr<const Clock> clock = system_clock());

  const std::string& name() const override { return inner_->name(); }
  Status open() override { return inner_->open(); }
  void close() override { inner_->close(); }
  // Only frames the inner bus accepted are reported: a failed send never reached the wire.
  Status send(const codec::CanFrame& frame) override;
  BatchSent send_batch(std::span<const codec::CanFrame> frames) override;
  std::optional<TimedFrame> receive(std::chrono::milliseconds timeout) override;
  std::size_t receive_batch(std::vector<TimedFrame>& out, std::size_t max,
                            std::chrono::milliseconds timeout) override;
  BusStatistics statistics() const override { return inner_->statistics(); }

  // Hands back the bus it wraps, unobserved: for when the observer is about to go. This
  // ObservedBus is then empty and may only be destroyed.
  std::unique_ptr<Bus> release() { return std::move(inner_); }

 private:
  std::unique_ptr<Bus> inner_;
  FrameObserver& observer_;
  const std::shared_ptr<const Clock> clock_;
};

}  // namespace teejet::can
