// Test peer for address_claim.sh and bench/run-shared-bus.sh: the other ECUs on a bus the
// gateway shares, on a real kernel (user-mode-linux). The kernel's own J1939 stack (can-j1939)
// is the judge that does not share the gateway's code: it learns NAME -> address only from the
// Address Claimed frames it sees on the bus, exactly as any other ISOBUS ECU would.
//
//   isobus_peer hold IFACE
//       Keeps a J1939 socket bound to IFACE, so that the kernel's J1939 instance there (and its
//       cache of claimed addresses) lives while the gateway claims, and prints each new
//       combination of PGN, source address, destination and the NAMEs the kernel gives them:
//         heard pgn=0x0EF00 from=0xD5 name=0x200880000541B2C3 to=0xD8 to_name=0x0
//   isobus_peer send IFACE (--from-name NAME | --from-address ADDR) --to-name NAME
//                    [--pgn PGN] [--data HEX]
//       One frame to a NAME, not an address: the kernel resolves the destination from its
//       cache. Exit 0 "sent", 2 "refused: EADDRNOTAVAIL" (no ECU holds an address with that
//       NAME, or the source NAME has none), 1 any other error.
//   isobus_peer ecu IFACE --name NAME --address ADDR --answers N
//       An ECU (plain CAN_RAW) that claims ADDR with NAME, answers the first N requests for
//       address claimed sent to ADDR or to everyone with its claim, and then stays silent
//       (prints "answered ..." / "silent to ..."), until SIGTERM: a contender for 0xD5 that
//       goes quiet, or a neighbour that stays.
//   isobus_peer foreign IFACE --rate FRAMES_PER_S [--seconds S]
//       Traffic of other ECUs that is none of the gateway's business: a cycle of 29-bit frames
//       of other PGNs and destinations (none from 0xD5, none to 0xD5 of PGN 0xEF00, no claim
//       0xEE00, no request 0xEA00) and 11-bit frames (0x0D5 among them), paced to the rate,
//       until SIGTERM or S seconds. Prints "foreign sent=N seconds=S rate=R enobufs=E".
// Usage errors exit 64.

#include <linux/can.h>
#include <linux/can/j1939.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <vector>

namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

void install_stop_handlers() {
  struct sigaction action {};
  action.sa_handler = on_signal;  // no SA_RESTART: a blocked recv returns EINTR
  sigaction(SIGTERM, &action, nullptr);
  sigaction(SIGINT, &action, nullptr);
}

[[noreturn]] void usage(const char* why) {
  std::fprintf(stderr,
               "isobus_peer: %s\nusage: isobus_peer hold IFACE\n"
               "       isobus_peer send IFACE (--from-name NAME | --from-address ADDR) "
               "--to-name NAME [--pgn PGN] [--data HEX]\n"
               "       isobus_peer ecu IFACE --name NAME --address ADDR --answers N\n"
               "       isobus_peer foreign IFACE --rate FRAMES_PER_S [--seconds S]\n",
               why);
  std::exit(64);
}

std::uint64_t number(const std::string& text, const char* what) {
  char* end = nullptr;
  errno = 0;
  const unsigned long long value = std::strtoull(text.c_str(), &end, 0);
  if (text.empty() || *end != '\0' || errno != 0) usage((std::string("bad ") + what).c_str());
  return value;
}

std::uint64_t hex_name(const std::string& text) {
  // NAMEs are written as 16 hex digits, with or without 0x, as the gateway logs them.
  const std::string digits = text.rfind("0x", 0) == 0 ? text.substr(2) : text;
  if (digits.size() != 16) usage("a NAME is 16 hexadecimal digits");
  return number("0x" + digits, "NAME");
}

std::vector<std::uint8_t> hex_bytes(const std::string& text) {
  if (text.size() % 2 != 0 || text.size() > 16) usage("--data takes up to 8 bytes in hex");
  std::vector<std::uint8_t> bytes;
  for (std::size_t i = 0; i < text.size(); i += 2) {
    bytes.push_back(static_cast<std::uint8_t>(number("0x" + text.substr(i, 2), "--data")));
  }
  return bytes;
}

unsigned interface_index(const std::string& interface) {
  const unsigned index = if_nametoindex(interface.c_str());
  if (index == 0) {
    std::fprintf(stderr, "isobus_peer: %s: %s\n", interface.c_str(), std::strerror(errno));
    std::exit(1);
  }
  return index;
}

// The options after MODE IFACE as name/value pairs.
struct Options {
  std::vector<std::pair<std::string, std::string>> values;
  std::optional<std::string> get(const std::string& name) const {
    for (const auto& [key, value] : values) {
      if (key == name) return value;
    }
    return std::nullopt;
  }
};

Options parse_options(int argc, char** argv, int first, const std::set<std::string>& known) {
  Options options;
  for (int i = first; i < argc; i += 2) {
    if (!known.count(argv[i])) usage((std::string("unknown option ") + argv[i]).c_str());
    if (i + 1 >= argc) usage((std::string(argv[i]) + " needs a value").c_str());
    options.values.emplace_back(argv[i], argv[i + 1]);
  }
  return options;
}

int j1939_socket() {
  const int fd = socket(PF_CAN, SOCK_DGRAM, CAN_J1939);
  if (fd < 0) {
    std::fprintf(stderr, "isobus_peer: CAN_J1939 socket: %s (is can-j1939 loaded?)\n",
                 std::strerror(errno));
    std::exit(1);
  }
  return fd;
}

sockaddr_can j1939_address(unsigned index, std::uint64_t name, std::uint32_t pgn,
                           std::uint8_t address) {
  sockaddr_can address_of{};
  address_of.can_family = AF_CAN;
  address_of.can_ifindex = static_cast<int>(index);
  address_of.can_addr.j1939.name = name;
  address_of.can_addr.j1939.pgn = pgn;
  address_of.can_addr.j1939.addr = address;
  return address_of;
}

// ---- hold -----------------------------------------------------------------------------------

int hold(const std::string& interface) {
  const unsigned index = interface_index(interface);
  const int fd = j1939_socket();
  const int on = 1;
  // Every PGN to every address, not only what is addressed to this socket.
  if (setsockopt(fd, SOL_CAN_J1939, SO_J1939_PROMISC, &on, sizeof on) < 0) {
    std::fprintf(stderr, "isobus_peer: SO_J1939_PROMISC: %s\n", std::strerror(errno));
    return 1;
  }
  const sockaddr_can bound = j1939_address(index, J1939_NO_NAME, J1939_NO_PGN, J1939_NO_ADDR);
  if (bind(fd, reinterpret_cast<const sockaddr*>(&bound), sizeof bound) < 0) {
    std::fprintf(stderr, "isobus_peer: bind %s: %s\n", interface.c_str(), std::strerror(errno));
    return 1;
  }
  std::printf("holding the J1939 instance of %s\n", interface.c_str());
  std::set<std::tuple<std::uint32_t, std::uint8_t, std::uint64_t, std::uint8_t, std::uint64_t>>
      seen;
  int errors_in_a_row = 0;
  while (!g_stop) {
    std::array<std::uint8_t, 1785> data{};
    sockaddr_can source{};
    iovec io{data.data(), data.size()};
    alignas(cmsghdr) std::array<char, 256> control{};
    msghdr message{};
    message.msg_name = &source;
    message.msg_namelen = sizeof source;
    message.msg_iov = &io;
    message.msg_iovlen = 1;
    message.msg_control = control.data();
    message.msg_controllen = control.size();
    if (recvmsg(fd, &message, 0) < 0) {
      if (errno == EINTR) continue;
      // A link that goes down reports ENETDOWN once; the socket works again when it is up.
      std::printf("recv error: %s\n", std::strerror(errno));
      if (++errors_in_a_row > 100) return 1;
      poll(nullptr, 0, 10);
      continue;
    }
    errors_in_a_row = 0;
    std::uint8_t destination = J1939_NO_ADDR;
    std::uint64_t destination_name = J1939_NO_NAME;
    for (cmsghdr* c = CMSG_FIRSTHDR(&message); c != nullptr; c = CMSG_NXTHDR(&message, c)) {
      if (c->cmsg_level != SOL_CAN_J1939) continue;
      if (c->cmsg_type == SCM_J1939_DEST_ADDR) {
        std::memcpy(&destination, CMSG_DATA(c), sizeof destination);
      } else if (c->cmsg_type == SCM_J1939_DEST_NAME) {
        std::memcpy(&destination_name, CMSG_DATA(c), sizeof destination_name);
      }
    }
    const auto& j = source.can_addr.j1939;
    if (seen.emplace(j.pgn, j.addr, j.name, destination, destination_name).second) {
      std::printf("heard pgn=0x%05X from=0x%02X name=0x%016llX to=0x%02X to_name=0x%016llX\n",
                  j.pgn, j.addr, static_cast<unsigned long long>(j.name), destination,
                  static_cast<unsigned long long>(destination_name));
    }
  }
  return 0;
}

// ---- send -----------------------------------------------------------------------------------

int send_by_name(const std::string& interface, const Options& options) {
  const auto to = options.get("--to-name");
  const auto from_name = options.get("--from-name");
  const auto from_address = options.get("--from-address");
  if (!to || from_name.has_value() == from_address.has_value()) {
    usage("send needs --to-name and one of --from-name, --from-address");
  }
  const auto pgn =
      static_cast<std::uint32_t>(number(options.get("--pgn").value_or("0xEF00"), "PGN"));
  const auto data = hex_bytes(options.get("--data").value_or("0102030405060708"));
  const unsigned index = interface_index(interface);
  const int fd = j1939_socket();
  // A source by NAME is resolved from the kernel's cache as the destination is; a source by
  // address is a static one (no claim of its own).
  const sockaddr_can bound =
      from_name ? j1939_address(index, hex_name(*from_name), J1939_NO_PGN, J1939_NO_ADDR)
                : j1939_address(index, J1939_NO_NAME, J1939_NO_PGN,
                                static_cast<std::uint8_t>(number(*from_address, "address")));
  if (bind(fd, reinterpret_cast<const sockaddr*>(&bound), sizeof bound) < 0) {
    std::printf("refused: bind: %s\n", std::strerror(errno));
    return 1;
  }
  const std::uint64_t name = hex_name(*to);
  const sockaddr_can destination = j1939_address(index, name, pgn, J1939_NO_ADDR);
  if (sendto(fd, data.data(), data.size(), 0, reinterpret_cast<const sockaddr*>(&destination),
             sizeof destination) < 0) {
    const int error = errno;
    std::printf("refused: %s: %s\n", error == EADDRNOTAVAIL ? "EADDRNOTAVAIL" : "error",
                std::strerror(error));
    return error == EADDRNOTAVAIL ? 2 : 1;
  }
  std::printf("sent pgn=0x%05X to NAME 0x%016llX\n", pgn, static_cast<unsigned long long>(name));
  return 0;
}

// ---- ecu and foreign: plain CAN_RAW -----------------------------------------------------

int raw_socket(unsigned index, const std::vector<can_filter>& filters) {
  const int fd = socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (fd < 0) {
    std::fprintf(stderr, "isobus_peer: CAN_RAW socket: %s\n", std::strerror(errno));
    std::exit(1);
  }
  // No filters: a socket that only sends takes no frame into its queue at all.
  if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, filters.empty() ? nullptr : filters.data(),
                 static_cast<socklen_t>(filters.size() * sizeof(can_filter))) < 0) {
    std::fprintf(stderr, "isobus_peer: CAN_RAW_FILTER: %s\n", std::strerror(errno));
    std::exit(1);
  }
  sockaddr_can bound{};
  bound.can_family = AF_CAN;
  bound.can_ifindex = static_cast<int>(index);
  if (bind(fd, reinterpret_cast<const sockaddr*>(&bound), sizeof bound) < 0) {
    std::fprintf(stderr, "isobus_peer: bind: %s\n", std::strerror(errno));
    std::exit(1);
  }
  return fd;
}

can_frame claim_frame(std::uint64_t name, std::uint8_t address) {
  can_frame frame{};
  frame.can_id = CAN_EFF_FLAG | 0x18EEFF00U | address;
  frame.len = 8;
  for (int i = 0; i < 8; ++i) frame.data[i] = static_cast<std::uint8_t>(name >> (8 * i));
  return frame;
}

bool write_frame(int fd, const can_frame& frame) {
  return write(fd, &frame, sizeof frame) == static_cast<ssize_t>(sizeof frame);
}

int ecu(const std::string& interface, const Options& options) {
  const auto name_text = options.get("--name");
  const auto address_text = options.get("--address");
  const auto answers_text = options.get("--answers");
  if (!name_text || !address_text || !answers_text) {
    usage("ecu needs --name, --address and --answers");
  }
  const std::uint64_t name = hex_name(*name_text);
  const auto address = static_cast<std::uint8_t>(number(*address_text, "address"));
  const auto answers = number(*answers_text, "--answers");
  // Requests (PGN 0xEA00) to this address and to everyone, from anyone.
  const std::vector<can_filter> requests{
      {CAN_EFF_FLAG | 0x00EA0000U | static_cast<canid_t>(address) << 8,
       CAN_EFF_FLAG | CAN_RTR_FLAG | 0x03FFFF00U},
      {CAN_EFF_FLAG | 0x00EAFF00U, CAN_EFF_FLAG | CAN_RTR_FLAG | 0x03FFFF00U}};
  const int fd = raw_socket(interface_index(interface), requests);
  if (!write_frame(fd, claim_frame(name, address))) {
    std::fprintf(stderr, "isobus_peer: claim: %s\n", std::strerror(errno));
    return 1;
  }
  std::printf("claimed 0x%02X as NAME 0x%016llX\n", address, static_cast<unsigned long long>(name));
  std::uint64_t answered = 0;
  while (!g_stop) {
    can_frame frame{};
    if (read(fd, &frame, sizeof frame) != static_cast<ssize_t>(sizeof frame)) {
      if (errno == EINTR) continue;
      std::printf("read error: %s\n", std::strerror(errno));
      // A link that goes down reports ENETDOWN once; the socket works again when it is up.
      if (errno == ENETDOWN) continue;
      return 1;
    }
    // Only a request for Address Claimed (PGN 0x00EE00 in its 3 data bytes) asks for a claim.
    if (frame.len != 3 || frame.data[0] != 0x00 || frame.data[1] != 0xEE || frame.data[2] != 0x00) {
      continue;
    }
    const unsigned id = frame.can_id & CAN_EFF_MASK;
    if (answered < answers) {
      if (!write_frame(fd, claim_frame(name, address))) {
        std::fprintf(stderr, "isobus_peer: claim: %s\n", std::strerror(errno));
        return 1;
      }
      ++answered;
      std::printf("answered request 0x%08X\n", id);
    } else {
      std::printf("silent to request 0x%08X\n", id);
    }
  }
  return 0;
}

// Other ECUs' traffic the gateway's kernel filters must keep out: none of it comes from 0xD5,
// is a claim or a request, or is PGN 0xEF00 to 0xD5 (a valve's frame to the gateway).
constexpr std::array<canid_t, 16> kForeignIds{
    CAN_EFF_FLAG | 0x0CF00400U,  // EEC1 from the engine (0x00)
    CAN_EFF_FLAG | 0x18FEF100U,  // CCVS, broadcast
    CAN_EFF_FLAG | 0x0CFE6CEEU,  // TCO1 from 0xEE (an address valves use, another PGN)
    CAN_EFF_FLAG | 0x18EF2080U,  // proprietary A, 0x80 to 0x20
    CAN_EFF_FLAG | 0x18EFD980U,  // proprietary A, 0x80 to valve 0xD9: another controller's
    CAN_EFF_FLAG | 0x1CECD580U,  // transport protocol to 0xD5 (not a request, not PGN 0xEF00)
    CAN_EFF_FLAG | 0x18EBD580U,  // transport data to 0xD5
    CAN_EFF_FLAG | 0x18E8FF80U,  // acknowledgement, global
    CAN_EFF_FLAG | 0x18FECAD4U,  // DM1 from 0xD4, the address below the gateway's
    CAN_EFF_FLAG | 0x18FFD5D6U,  // proprietary B (PS 0xD5 is a group extension, not a target)
    CAN_EFF_FLAG | 0x0CFE4980U,  // ground-based speed
    CAN_EFF_FLAG | 0x18EFD4D8U,  // proprietary A from 0xD8 to 0xD4, not to 0xD5
    0x0D5U,                      // 11-bit: its low byte matches 0xD5, its format does not
    0x123U,
    0x7DFU,
    0x1D5U,
};

double now_seconds() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<double>(now.tv_sec) + static_cast<double>(now.tv_nsec) / 1e9;
}

int foreign(const std::string& interface, const Options& options) {
  const auto rate_text = options.get("--rate");
  if (!rate_text) usage("foreign needs --rate");
  const double rate = static_cast<double>(number(*rate_text, "--rate"));
  const double seconds = static_cast<double>(number(options.get("--seconds").value_or("0"), "s"));
  if (rate <= 0) usage("--rate must be positive");
  const int fd = raw_socket(interface_index(interface), {});
  // Bursts every 5 ms: a sleep per frame at 2,000/s is below what a guest timer keeps.
  constexpr double kBurstPeriod = 0.005;
  const double started = now_seconds();
  std::uint64_t sent = 0;
  std::uint64_t enobufs = 0;
  std::uint64_t counter = 0;
  for (double next = started; !g_stop;) {
    const double now = now_seconds();
    if (seconds > 0 && now - started >= seconds) break;
    const auto due = static_cast<std::uint64_t>((now - started) * rate);
    while (sent < due && !g_stop) {
      can_frame frame{};
      frame.can_id = kForeignIds[counter % kForeignIds.size()];
      frame.len = static_cast<std::uint8_t>(1 + counter % 8);
      for (int i = 0; i < 8; ++i) frame.data[i] = static_cast<std::uint8_t>(counter >> (8 * i));
      ++counter;
      if (write_frame(fd, frame)) {
        ++sent;
        continue;
      }
      if (errno == ENOBUFS) {
        ++enobufs;  // the device queue is full: wait until the next burst
        break;
      }
      if (errno == EINTR) continue;
      std::fprintf(stderr, "isobus_peer: write: %s\n", std::strerror(errno));
      return 1;
    }
    next += kBurstPeriod;
    const double wait = next - now_seconds();
    if (wait > 0) {
      const timespec pause{0, static_cast<long>(wait * 1e9)};
      nanosleep(&pause, nullptr);
    } else {
      next = now_seconds();  // behind: never burst to catch up more than one period
    }
  }
  const double elapsed = now_seconds() - started;
  std::printf("foreign sent=%llu seconds=%.1f rate=%.0f enobufs=%llu\n",
              static_cast<unsigned long long>(sent), elapsed,
              elapsed > 0 ? static_cast<double>(sent) / elapsed : 0.0,
              static_cast<unsigned long long>(enobufs));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Line by line: a script reads these files while the peer runs.
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  if (argc < 3) usage("a mode and an interface, please");
  install_stop_handlers();
  const std::string mode = argv[1];
  const std::string interface = argv[2];
  if (mode == "hold") {
    if (argc != 3) usage("hold takes no options");
    return hold(interface);
  }
  if (mode == "send") {
    return send_by_name(interface, parse_options(argc, argv, 3,
                                                 {"--from-name", "--from-address", "--to-name",
                                                  "--pgn", "--data"}));
  }
  if (mode == "ecu") {
    return ecu(interface, parse_options(argc, argv, 3, {"--name", "--address", "--answers"}));
  }
  if (mode == "foreign") {
    return foreign(interface, parse_options(argc, argv, 3, {"--rate", "--seconds"}));
  }
  usage(("unknown mode " + mode).c_str());
}
