#include "teejet/can/bus.hpp"

#include "teejet/codec/can_id.hpp"

namespace teejet::can {

std::vector<Filter> controller_side_filters() {
  return {{codec::from_valve_id(0), 0xFFFFFF00}};  // 0x18EFD5xx
}

std::vector<Filter> valve_side_filters() {
  return {{codec::to_valve_id(0), 0xFFFF00FF}};  // 0x18EFxxD5
}

std::size_t Bus::receive_batch(std::vector<TimedFrame>& out, std::size_t max,
                               std::chrono::milliseconds timeout) {
  std::size_t taken = 0;
  while (taken < max) {
    auto frame = receive(taken == 0 ? timeout : std::chrono::milliseconds{0});
    if (!frame) break;
    out.push_back(std::move(*frame));
    ++taken;
  }
  return taken;
}

Bus::BatchSent Bus::send_batch(std::span<const codec::CanFrame> frames) {
  BatchSent result;
  for (const auto& frame : frames) {
    result.status = send(frame);
    if (!result.status) break;
    ++result.sent;
  }
  return result;
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
