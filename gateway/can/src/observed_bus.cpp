#include "teejet/can/observed_bus.hpp"

namespace teejet::can {

ObservedBus::ObservedBus(std::unique_ptr<Bus> inner, FrameObserver& observer,
                         std::shared_ptr<const Clock> clock)
    : inner_(std::move(inner)), observer_(observer), clock_(std::move(clock)) {}

Status ObservedBus::send(const codec::CanFrame& frame) {
  auto sent = inner_->send(frame);
  if (sent) observer_.on_frame(frame, FrameDirection::kSent, clock_->wall());
  return sent;
}

// The inner bus's own send_batch, not send() per frame: the virtual bus delivers a burst at
// once, and wrapping must not change what the wire sees.
Bus::BatchSent ObservedBus::send_batch(std::span<const codec::CanFrame> frames) {
  auto result = inner_->send_batch(frames);
  if (result.sent > 0) {
    const Timestamp stamp = clock_->wall();
    for (const auto& frame : frames.first(result.sent)) {
      observer_.on_frame(frame, FrameDirection::kSent, stamp);
    }
  }
  return result;
}

std::optional<TimedFrame> ObservedBus::receive(std::chrono::milliseconds timeout) {
  auto received = inner_->receive(timeout);
  if (received) observer_.on_frame(received->frame, FrameDirection::kReceived, received->received);
  return received;
}

std::size_t ObservedBus::receive_batch(std::vector<TimedFrame>& out, std::size_t max,
                                       std::chrono::milliseconds timeout) {
  const std::size_t before = out.size();
  const std::size_t taken = inner_->receive_batch(out, max, timeout);
  for (std::size_t i = before; i < before + taken; ++i) {
    observer_.on_frame(out[i].frame, FrameDirection::kReceived, out[i].received);
  }
  return taken;
}

}  // namespace teejet::can
