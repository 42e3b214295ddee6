#include "listen_address.hpp"

#include <arpa/inet.h>

#include <charconv>

namespace teejet::web {

Result<std::string> parse_listen(std::string_view text, std::string_view option,
                                 std::string_view example) {
  const auto fail = [&](const std::string& why) {
    return Error{ErrorCode::kInvalidValue,
                 std::string(option) + " '" + std::string(text) + "': " + why};
  };
  const auto colon = text.rfind(':');
  if (colon == std::string_view::npos) {
    return fail("expected ADDR:PORT, e.g. " + std::string(example));
  }
  std::string host(text.substr(0, colon));
  const std::string_view port_text = text.substr(colon + 1);
  unsigned port = 0;
  const auto [end, error] =
      std::from_chars(port_text.data(), port_text.data() + port_text.size(), port);
  if (port_text.empty() || error != std::errc{} || end != port_text.data() + port_text.size() ||
      port < 1 || port > 65535) {
    return fail("the port must be a number from 1 to 65535");
  }
  // A host name, or an empty address, could mean every interface: only literals.
  unsigned char address[16];
  if (host.size() > 2 && host.front() == '[' && host.back() == ']') {
    if (inet_pton(AF_INET6, host.substr(1, host.size() - 2).c_str(), address) != 1) {
      return fail("'" + host + "' is not an IPv6 address");
    }
  } else if (inet_pton(AF_INET, host.c_str(), address) != 1) {
    return fail("'" + host + "' is not an IPv4 address (IPv6 in brackets: [::1]:8080)");
  }
  return host + ':' + std::to_string(port);
}

}  // namespace teejet::web
