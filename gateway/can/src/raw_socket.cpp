#include "raw_socket.hpp"

#include <linux/can/raw.h>
#include <linux/net_tstamp.h>
#include <linux/sock_diag.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>

#include "kernel_frame.hpp"

namespace teejet::can {
namespace {

Error missing_interface(const std::string& interface) {
  return Error{ErrorCode::kUnavailable, interface + ": no such interface", ENODEV};
}

}  // namespace

bool is_missing_interface(const Error& error) {
  return error.code == ErrorCode::kUnavailable && error.os_error == ENODEV;
}

RawSocket::~RawSocket() { ::close(fd_); }

Result<OpenedSocket> open_socket(const std::string& interface, const SocketCanOptions& options) {
  if (interface.empty() || interface.size() >= IFNAMSIZ) {
    std::string reason = "'";
    reason += interface;
    reason += "' is not a network interface name";
    return Error{ErrorCode::kInvalidValue, std::move(reason), EINVAL};
  }
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) {
    const int error_number = errno;
    return Error{ErrorCode::kSystem,
                 interface + ": cannot create a CAN_RAW socket (" + error_text(error_number) +
                     "; is the can-raw module loaded?)",
                 error_number};
  }
  auto socket = std::make_shared<RawSocket>(fd);
  const auto fail = [&](const char* what) {
    const int error_number = errno;
    return Error{ErrorCode::kSystem, interface + ": " + what + ": " + error_text(error_number),
                 error_number};
  };

  const std::vector<can_filter> filters = kernel_filters(options.filters);
  if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, filters.data(),
                   static_cast<socklen_t>(filters.size() * sizeof(can_filter))) < 0) {
    return fail("CAN_RAW_FILTER");
  }
  const can_err_mask_t error_mask = CAN_ERR_MASK;
  if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &error_mask, sizeof error_mask) < 0) {
    return fail("CAN_RAW_ERR_FILTER");
  }
  // Loopback stays on so that other sockets on this host (candump, a simulator) see our frames;
  // our own frames are not received back.
  const int on = 1, off = 0;
  if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_LOOPBACK, &on, sizeof on) < 0) {
    return fail("CAN_RAW_LOOPBACK");
  }
  if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, &off, sizeof off) < 0) {
    return fail("CAN_RAW_RECV_OWN_MSGS");
  }
  // Kernel receive time: SO_TIMESTAMPING software RX, else SO_TIMESTAMPNS. Without either, the
  // frame is stamped when read (both exist since long before any kernel we run on).
  const int stamping = SOF_TIMESTAMPING_RX_SOFTWARE | SOF_TIMESTAMPING_SOFTWARE;
  if (::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPING, &stamping, sizeof stamping) < 0) {
    (void)::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on);
  }
  if (::setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on) < 0) return fail("SO_RXQ_OVFL");
  const int receive_buffer = options.receive_buffer_bytes;
  if (receive_buffer > 0 &&
      ::setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &receive_buffer, sizeof receive_buffer) < 0 &&
      ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &receive_buffer, sizeof receive_buffer) < 0) {
    return fail("SO_RCVBUF");
  }

  const unsigned ifindex = ::if_nametoindex(interface.c_str());
  if (ifindex == 0) return missing_interface(interface);
  sockaddr_can address{};
  address.can_family = AF_CAN;
  address.can_ifindex = static_cast<int>(ifindex);
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) < 0) {
    const int error_number = errno;
    // CAN_RAW refuses a device that is not CAN with ENODEV; one deleted since the lookup
    // above gives the same errno and is missing, not wrong.
    if (error_number == ENODEV) {
      if (::if_nametoindex(interface.c_str()) != ifindex) return missing_interface(interface);
      return Error{ErrorCode::kInvalidValue,
                   interface + ": not a CAN interface (bind: " + error_text(error_number) + ")",
                   error_number};
    }
    errno = error_number;
    return fail("bind");
  }
  return OpenedSocket{std::move(socket), static_cast<int>(ifindex)};
}

std::optional<bool> interface_up(int fd, const std::string& interface) {
  ifreq request{};
  std::memcpy(request.ifr_name, interface.data(),
              std::min<std::size_t>(interface.size(), IFNAMSIZ - 1));
  if (::ioctl(fd, SIOCGIFFLAGS, &request) < 0) return std::nullopt;
  return (request.ifr_flags & IFF_UP) != 0;
}

std::optional<std::uint32_t> kernel_drop_counter(int fd) {
  std::array<std::uint32_t, SK_MEMINFO_VARS> info{};
  socklen_t length = sizeof info;
  if (::getsockopt(fd, SOL_SOCKET, SO_MEMINFO, info.data(), &length) == 0 &&
      length >= (SK_MEMINFO_DROPS + 1) * sizeof(std::uint32_t)) {
    return info[SK_MEMINFO_DROPS];
  }
  return std::nullopt;
}

int write_frame(int fd, const can_frame& frame) {
  const ssize_t written = ::write(fd, &frame, sizeof frame);
  if (written == static_cast<ssize_t>(sizeof frame)) return 0;
  return written < 0 ? errno : EIO;
}

bool is_vanished_error(int error_number) {
  return error_number == ENODEV || error_number == ENXIO || error_number == EBADF;
}

std::string error_text(int error_number) { return std::strerror(error_number); }

}  // namespace teejet::can
