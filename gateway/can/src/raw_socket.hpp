#pragma once

// The CAN_RAW socket and the few system calls made on it: creating, configuring and binding it,
// asking the interface's flags and the kernel's drop counter, writing one frame. Small helpers
// shared by the sending and the receiving side of SocketCanBus; what a failure means for the
// link (down, gone) is decided there, not here.

#include <linux/can.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "teejet/can/socketcan_bus.hpp"

namespace teejet::can {

// A socket descriptor, closed when the last holder lets go: a receiver in poll() keeps it valid
// while another thread replaces or closes the bus's socket.
class RawSocket {
 public:
  explicit RawSocket(int fd) : fd_(fd) {}
  ~RawSocket();
  RawSocket(const RawSocket&) = delete;
  RawSocket& operator=(const RawSocket&) = delete;
  int fd() const { return fd_; }

 private:
  int fd_;
};
using SocketPtr = std::shared_ptr<RawSocket>;

struct OpenedSocket {
  SocketPtr socket;
  int ifindex = 0;
};

// Creates a non-blocking CAN_RAW socket, configures it (kernel filters, every error class,
// loopback on but not our own frames back, kernel receive stamps, the drop counter, the receive
// buffer) and binds it to `interface` by name. On failure, says why with errno.
Result<OpenedSocket> open_socket(const std::string& interface, const SocketCanOptions& options);

// open_socket()'s error for an interface that does not exist (yet): the one failure that waiting
// can cure, unlike a name that is too long or names an interface that is not CAN.
bool is_missing_interface(const Error& error);

// IFF_UP of the interface, asked through the socket: nullopt with errno set when that fails.
std::optional<bool> interface_up(int fd, const std::string& interface);

// The kernel's cumulative drop counter of the socket (SO_MEMINFO), known without reading a frame.
std::optional<std::uint32_t> kernel_drop_counter(int fd);

// Writes one frame without blocking: 0 when it was written, else the errno (EIO: short write).
int write_frame(int fd, const can_frame& frame);

// The errno values that mean the interface itself vanished (deleted or unregistered), as
// opposed to ENETDOWN, where it still exists with its link down.
bool is_vanished_error(int error_number);

std::string error_text(int error_number);

}  // namespace teejet::can
