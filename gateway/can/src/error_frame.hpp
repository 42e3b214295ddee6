#pragma once

// Pure decoding of SocketCAN error frames (linux/can/error.h) into controller state. No sockets,
// no kernel: unit-tested on hand-built frames.

#include <array>
#include <cstdint>
#include <optional>

#include "teejet/can/bus.hpp"

namespace teejet::can {

// What one error frame says. An error frame is a classic CAN frame whose can_id carries
// CAN_ERR_FLAG; the low bits are the error classes, the eight data bytes the details.
struct ErrorFrameReport {
  std::uint32_t error_classes = 0;  // can_id & CAN_ERR_MASK (CAN_ERR_BUSOFF, CAN_ERR_CRTL, ...)
  std::optional<BusState> state;    // the controller state the frame announces, if any
  // data[1] without CAN_ERR_CRTL_ACTIVE, when CAN_ERR_CRTL is set; 0 after a restart.
  std::optional<std::uint32_t> controller_problems;
  // data[6] / data[7] when CAN_ERR_CNT is set; 0 after a restart that carries no counters.
  std::optional<std::uint8_t> tx_errors;
  std::optional<std::uint8_t> rx_errors;
};

// True when a raw SocketCAN can_id (flag bits included) is an error frame.
bool is_error_frame(std::uint32_t raw_can_id);

// Decodes one error frame: raw_can_id with its flag bits, the data bytes as received (an error
// frame always has CAN_ERR_DLC = 8). State precedence: bus-off, then restarted (error-active),
// then the controller bits passive > warning > active.
ErrorFrameReport decode_error_frame(std::uint32_t raw_can_id,
                                    const std::array<std::uint8_t, 8>& data);

// The controller as error frames describe it.
struct ControllerStatus {
  BusState state = BusState::kErrorActive;
  std::uint16_t tx_errors = 0;
  std::uint16_t rx_errors = 0;
  std::uint32_t controller_problems = 0;
  std::uint64_t error_frames = 0;
};

// Folds one report into the status; returns true when the controller state changed.
bool apply(const ErrorFrameReport& report, ControllerStatus& status);

}  // namespace teejet::can
