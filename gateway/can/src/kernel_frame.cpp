#include "kernel_frame.hpp"

#include <algorithm>
#include <iterator>

namespace teejet::can {

bool is_classic_frame(const codec::CanFrame& frame) {
  return frame.dlc <= codec::CanFrame::kMaxData &&
         frame.id <= (frame.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
}

can_frame to_kernel(const codec::CanFrame& frame) {
  can_frame out{};
  out.can_id = frame.extended ? (frame.id & CAN_EFF_MASK) | CAN_EFF_FLAG : frame.id & CAN_SFF_MASK;
  if (frame.remote) out.can_id |= CAN_RTR_FLAG;
  out.len = std::min<std::uint8_t>(frame.dlc, codec::CanFrame::kMaxData);
  std::copy_n(frame.data.begin(), out.len, out.data);
  return out;
}

codec::CanFrame from_kernel(const can_frame& frame) {
  codec::CanFrame out;
  out.extended = (frame.can_id & CAN_EFF_FLAG) != 0;
  out.remote = (frame.can_id & CAN_RTR_FLAG) != 0;
  out.id = frame.can_id & (out.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
  out.dlc = std::min<std::uint8_t>(frame.len, codec::CanFrame::kMaxData);
  std::copy_n(frame.data, out.dlc, out.data.begin());
  return out;
}

can_filter kernel_filter(const Filter& filter) {
  return {(filter.id & CAN_EFF_MASK) | CAN_EFF_FLAG,
          (filter.mask & CAN_EFF_MASK) | CAN_EFF_FLAG | CAN_RTR_FLAG};
}

std::vector<can_filter> kernel_filters(const std::vector<Filter>& filters) {
  if (filters.empty()) return {{CAN_EFF_FLAG, CAN_EFF_FLAG | CAN_RTR_FLAG}};
  std::vector<can_filter> out;
  out.reserve(filters.size());
  std::transform(filters.begin(), filters.end(), std::back_inserter(out), kernel_filter);
  return out;
}

Timestamp to_timestamp(const timespec& stamp) {
  return Timestamp{std::chrono::seconds{stamp.tv_sec} + std::chrono::nanoseconds{stamp.tv_nsec}};
}

std::uint32_t drops_since(std::uint32_t before, std::uint32_t now) {
  const auto delta = static_cast<std::uint32_t>(now - before);
  return delta < 0x80000000U ? delta : 0;
}

}  // namespace teejet::can
