#pragma once

// Receiving in batches: one recvmmsg call reads up to kReceiveBatch frames, each with its
// control messages (the kernel's receive stamp and drop counter). Error frames are decoded,
// data frames converted and stamped. Nothing here locks: SocketCanBus reads a batch without its
// mutex and folds it into its state afterwards.

#include <sys/socket.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "error_frame.hpp"
#include "teejet/can/bus.hpp"

namespace teejet::can {

inline constexpr std::size_t kReceiveBatch = 32;  // frames read per recvmmsg

// What one recvmmsg call brought, handed from the lock-free read to the locked bookkeeping.
struct ReadBatch {
  std::vector<TimedFrame> frames;
  std::vector<ErrorFrameReport> errors;
  std::optional<std::uint32_t> drop_counter;  // newest SO_RXQ_OVFL value seen
  int error_number = 0;                       // recvmmsg failed with this
};

// What the control messages of one received frame say.
struct ReceiveControl {
  std::optional<Timestamp> stamp;  // SCM_TIMESTAMPING ts[0] (software), or SCM_TIMESTAMPNS
  std::optional<std::uint32_t> drop_counter;  // SO_RXQ_OVFL: sent only once it is non-zero
};

// Reads the control messages of one received message. A software stamp of 0 (none taken) is no
// stamp. Pure: takes what recvmmsg filled in, calls nothing.
ReceiveControl read_control(msghdr& header);

// One non-blocking recvmmsg on `fd`. Frames without a kernel stamp are stamped when read.
ReadBatch read_batch(int fd);

}  // namespace teejet::can
