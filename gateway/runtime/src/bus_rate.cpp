#include "teejet/gateway/bus_rate.hpp"

namespace teejet::gateway {

namespace {

bool at_least(std::size_t frames, Duration length, unsigned per_second) {
  return static_cast<double>(frames) >= per_second * std::chrono::duration<double>(length).count();
}

}  // namespace

BusRate::BusRate(unsigned above, SteadyTime now) : above_(above), since_(now), busy_(above == 0) {}

void BusRate::count(std::size_t frames, SteadyTime now) {
  counted_ += frames;
  const Duration length = now - since_;
  if (length < kStep || above_ == 0) return;
  const Step latest{counted_, length};
  steps_[next_] = latest;
  next_ = (next_ + 1) % kSteps;
  if (filled_ < kSteps) ++filled_;
  counted_ = 0;
  since_ = now;

  Step second;
  for (std::size_t i = 0; i < filled_; ++i) {
    second.frames += steps_[i].frames;
    second.length += steps_[i].length;
  }
  busy_ = filled_ == kSteps && at_least(second.frames, second.length, above_) &&
          at_least(latest.frames, latest.length, above_);
}

}  // namespace teejet::gateway
