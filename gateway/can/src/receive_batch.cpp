#include "receive_batch.hpp"

#include <linux/can.h>
#include <linux/errqueue.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <ctime>

#include "kernel_frame.hpp"

namespace teejet::can {
namespace {

Timestamp realtime_now() {
  timespec now{};
  ::clock_gettime(CLOCK_REALTIME, &now);
  return to_timestamp(now);
}

}  // namespace

ReceiveControl read_control(msghdr& header) {
  ReceiveControl out;
  for (cmsghdr* c = CMSG_FIRSTHDR(&header); c != nullptr; c = CMSG_NXTHDR(&header, c)) {
    if (c->cmsg_level != SOL_SOCKET) continue;
    if (c->cmsg_type == SCM_TIMESTAMPING) {
      scm_timestamping stamps;
      std::memcpy(&stamps, CMSG_DATA(c), sizeof stamps);
      if (stamps.ts[0].tv_sec != 0 || stamps.ts[0].tv_nsec != 0) {
        out.stamp = to_timestamp(stamps.ts[0]);  // [0]: software; [2] would be hardware
      }
    } else if (c->cmsg_type == SCM_TIMESTAMPNS) {
      timespec stamp;
      std::memcpy(&stamp, CMSG_DATA(c), sizeof stamp);
      out.stamp = to_timestamp(stamp);
    } else if (c->cmsg_type == SO_RXQ_OVFL) {
      std::uint32_t drops;
      std::memcpy(&drops, CMSG_DATA(c), sizeof drops);
      out.drop_counter = drops;
    }
  }
  return out;
}

ReadBatch read_batch(int fd) {
  struct Slot {
    can_frame frame;
    iovec vector;
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(scm_timestamping)) +
                                  CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(std::uint32_t))];
  };
  std::array<Slot, kReceiveBatch> slots;
  std::array<mmsghdr, kReceiveBatch> messages{};
  for (std::size_t i = 0; i < kReceiveBatch; ++i) {
    slots[i].vector = {&slots[i].frame, sizeof(can_frame)};
    messages[i].msg_hdr.msg_iov = &slots[i].vector;
    messages[i].msg_hdr.msg_iovlen = 1;
    messages[i].msg_hdr.msg_control = slots[i].control;
    messages[i].msg_hdr.msg_controllen = sizeof slots[i].control;
  }
  ReadBatch batch;
  const int count = ::recvmmsg(fd, messages.data(), kReceiveBatch, MSG_DONTWAIT, nullptr);
  if (count < 0) {
    batch.error_number = errno;
    return batch;
  }
  batch.frames.reserve(static_cast<std::size_t>(count));
  for (std::size_t i = 0; i < static_cast<std::size_t>(count); ++i) {
    msghdr& header = messages[i].msg_hdr;
    if (messages[i].msg_len != sizeof(can_frame) || (header.msg_flags & MSG_TRUNC)) continue;
    const ReceiveControl control = read_control(header);
    if (control.drop_counter) batch.drop_counter = control.drop_counter;
    const can_frame& frame = slots[i].frame;
    if (is_error_frame(frame.can_id)) {
      std::array<std::uint8_t, 8> data{};
      std::copy_n(frame.data, std::min<std::size_t>(frame.len, data.size()), data.begin());
      batch.errors.push_back(decode_error_frame(frame.can_id, data));
    } else {
      batch.frames.push_back({from_kernel(frame), control.stamp ? *control.stamp : realtime_now()});
    }
  }
  return batch;
}

}  // namespace teejet::can
