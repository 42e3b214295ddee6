#include "teejet/can/bus.hpp"

#include "teejet/codec/can_id.hpp"

namespace teejet::can {
namespace {

class SystemClock final : public Clock {
 public:
  Timestamp now() const override {
    return std::chrono::duration_cast<Timestamp>(
        std::chrono::system_clock::now().time_since_epoch());
  }
};

}  // namespace

std::shared_ptr<const Clock> system_clock() {
  static const auto clock = std::make_shared<const SystemClock>();
  return clock;
}

std::vector<Filter> controller_side_filters() {
  return {{codec::from_valve_id(0), 0xFFFFFF00}};  // 0x18EFD5xx
}

std::vector<Filter> valve_side_filters() {
  return {{codec::to_valve_id(0), 0xFFFF00FF}};  // 0x18EFxxD5
}

const char* to_string(BusState state) {
  switch (state) {
    case BusState::kErrorActive:
      return "error-active";
    case BusState::kErrorWarning:
      return "error-warning";
    case BusState::kErrorPassive:
      return "error-passive";
    case BusState::kBusOff:
      return "bus-off";
    case BusState::kDown:
      return "down";
  }
  return "unknown";
}

}  // namespace teejet::can
