#include "teejet/core/time.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace teejet {
namespace {

class SystemClock final : public Clock {
 public:
  Timestamp wall() const override {
    return std::chrono::time_point_cast<Duration>(std::chrono::system_clock::now());
  }
  SteadyTime steady() const override {
    return std::chrono::time_point_cast<Duration>(std::chrono::steady_clock::now());
  }
};

}  // namespace

std::uint64_t unix_nanoseconds(Timestamp time) {
  const auto count = time.time_since_epoch().count();
  return count < 0 ? 0 : static_cast<std::uint64_t>(count);
}

Timestamp from_unix_nanoseconds(std::uint64_t nanoseconds) {
  constexpr auto kMax = static_cast<std::uint64_t>(std::numeric_limits<Duration::rep>::max());
  return Timestamp{Duration{static_cast<Duration::rep>(std::min(nanoseconds, kMax))}};
}

Duration seconds(double value) {
  if (!(value > 0)) return Duration{0};
  constexpr double kMaxSeconds =
      static_cast<double>(std::numeric_limits<Duration::rep>::max()) / 1e9;
  if (value >= kMaxSeconds) return Duration::max();
  return Duration{static_cast<Duration::rep>(std::llround(value * 1e9))};
}

std::shared_ptr<const Clock> system_clock() {
  static const auto clock = std::make_shared<const SystemClock>();
  return clock;
}

ManualClock::ManualClock(Timestamp wall_start, SteadyTime steady_start)
    : wall_(wall_start.time_since_epoch().count()),
      steady_(steady_start.time_since_epoch().count()) {}

Timestamp ManualClock::wall() const { return Timestamp{Duration{wall_.load()}}; }
SteadyTime ManualClock::steady() const { return SteadyTime{Duration{steady_.load()}}; }

void ManualClock::advance(Duration by) {
  wall_ += by.count();
  steady_ += by.count();
}

void ManualClock::step_wall(Duration by) { wall_ += by.count(); }

}  // namespace teejet
