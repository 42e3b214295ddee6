#include "error_frame.hpp"

#include <linux/can.h>
#include <linux/can/error.h>

namespace teejet::can {

bool is_error_frame(std::uint32_t raw_can_id) { return (raw_can_id & CAN_ERR_FLAG) != 0; }

ErrorFrameReport decode_error_frame(std::uint32_t raw_can_id,
                                    const std::array<std::uint8_t, 8>& data) {
  ErrorFrameReport report;
  report.error_classes = raw_can_id & CAN_ERR_MASK;
  const std::uint32_t classes = report.error_classes;

  if (classes & CAN_ERR_CRTL) {
    const std::uint8_t bits = data[1];
    report.controller_problems = bits & ~std::uint32_t{CAN_ERR_CRTL_ACTIVE};
    if (bits & (CAN_ERR_CRTL_TX_PASSIVE | CAN_ERR_CRTL_RX_PASSIVE)) {
      report.state = BusState::kErrorPassive;
    } else if (bits & (CAN_ERR_CRTL_TX_WARNING | CAN_ERR_CRTL_RX_WARNING)) {
      report.state = BusState::kErrorWarning;
    } else if (bits & CAN_ERR_CRTL_ACTIVE) {
      report.state = BusState::kErrorActive;
    }
  }
  if (classes & CAN_ERR_RESTARTED) {
    // A restart (after bus-off) resets the controller and its error counters.
    report.state = BusState::kErrorActive;
    report.controller_problems = 0;
    report.tx_errors = 0;
    report.rx_errors = 0;
  }
  if (classes & CAN_ERR_BUSOFF) report.state = BusState::kBusOff;
  if (classes & CAN_ERR_CNT) {
    report.tx_errors = data[6];
    report.rx_errors = data[7];
  }
  return report;
}

bool apply(const ErrorFrameReport& report, ControllerStatus& status) {
  ++status.error_frames;
  if (report.controller_problems) status.controller_problems = *report.controller_problems;
  if (report.tx_errors) status.tx_errors = *report.tx_errors;
  if (report.rx_errors) status.rx_errors = *report.rx_errors;
  if (!report.state || *report.state == status.state) return false;
  status.state = *report.state;
  return true;
}

}  // namespace teejet::can
