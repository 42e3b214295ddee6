#include "request_guard.hpp"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <netinet/in.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <optional>

namespace teejet::web {
namespace {

// An address literal in inet_ntop's form ("::1" for "0:0::1"); nullopt when it is none.
std::optional<std::string> canonical_address(const std::string& text, int family) {
  unsigned char bytes[16];
  char out[INET6_ADDRSTRLEN];
  if (inet_pton(family, text.c_str(), bytes) != 1) return std::nullopt;
  if (inet_ntop(family, bytes, out, sizeof out) == nullptr) return std::nullopt;
  return std::string(out);
}

std::string lower(std::string_view text) {
  std::string lowered(text);
  std::transform(lowered.begin(), lowered.end(), lowered.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return lowered;
}

bool contains(const std::vector<std::string>& list, const std::string& item) {
  return std::find(list.begin(), list.end(), item) != list.end();
}

struct HostAndPort {
  std::string host;  // an address in canonical form, or a lower-case name
  bool literal = false;
  unsigned port = 0;
};

// "[::1]:8080", "127.0.0.1:8080", "Bench:8080", "bench" (port 80); nullopt when malformed.
std::optional<HostAndPort> split_host(std::string_view text) {
  std::string_view host = text;
  std::optional<std::string_view> port_text;
  const bool bracketed = !text.empty() && text.front() == '[';
  if (bracketed) {
    const auto close = text.find(']');
    if (close == std::string_view::npos) return std::nullopt;
    host = text.substr(1, close - 1);
    const std::string_view rest = text.substr(close + 1);
    if (!rest.empty()) {
      if (rest.front() != ':') return std::nullopt;
      port_text = rest.substr(1);
    }
  } else if (const auto colon = text.find(':'); colon != std::string_view::npos) {
    host = text.substr(0, colon);
    port_text = text.substr(colon + 1);
  }
  if (host.empty()) return std::nullopt;
  HostAndPort split;
  split.port = 80;
  if (port_text) {
    const auto [end, error] =
        std::from_chars(port_text->data(), port_text->data() + port_text->size(), split.port);
    if (port_text->empty() || error != std::errc{} ||
        end != port_text->data() + port_text->size()) {
      return std::nullopt;
    }
  }
  const auto address = canonical_address(std::string(host), bracketed ? AF_INET6 : AF_INET);
  if (bracketed && !address) return std::nullopt;
  split.host = address ? *address : lower(host);
  split.literal = address.has_value();
  return split;
}

bool is_loopback(const std::string& address) {
  return address == "::1" || address.rfind("127.", 0) == 0;
}

// A whole answer with the security headers, after which the connection is closed.
std::string closing_answer(std::string_view status, std::string_view reason) {
  std::string answer = "HTTP/1.1 " + std::string(status) + "\r\n";
  for (const Header& header : kSecurityHeaders) {
    answer.append(header.name).append(": ").append(header.value).append("\r\n");
  }
  return answer + "Content-Type: text/plain; charset=utf-8\r\nContent-Length: " +
         std::to_string(reason.size()) + "\r\nConnection: close\r\n\r\n" + std::string(reason);
}

}  // namespace

AllowedHosts allowed_hosts(std::string_view listen, const std::vector<std::string>& local_addresses,
                           const std::vector<std::string>& names) {
  AllowedHosts allowed;
  const auto split = split_host(listen);
  if (!split) return allowed;  // parse_listen() made `listen`: never reached
  allowed.port = static_cast<std::uint16_t>(split->port);
  const bool every_interface = split->host == "0.0.0.0" || split->host == "::";
  if (every_interface) {
    for (const std::string& address : local_addresses) {
      const auto canonical = canonical_address(address, AF_INET)
                                 ? canonical_address(address, AF_INET)
                                 : canonical_address(address, AF_INET6);
      if (canonical) allowed.addresses.push_back(*canonical);
    }
  } else {
    allowed.addresses.push_back(split->host);
  }
  if (every_interface || is_loopback(split->host)) allowed.names.emplace_back("localhost");
  for (const std::string& name : names) allowed.names.push_back(lower(name));
  return allowed;
}

bool loopback_listen(std::string_view listen) {
  const auto split = split_host(listen);
  return split && is_loopback(split->host);
}

bool host_allowed(std::string_view host, const AllowedHosts& allowed) {
  const auto split = split_host(host);
  if (!split || split->port != allowed.port) return false;
  return contains(split->literal ? allowed.addresses : allowed.names, split->host);
}

std::string forbidden_host_answer() {
  return closing_answer("403 Forbidden",
                        "teejet-web does not serve this Host name: open it by the address it "
                        "listens on, or start it with --allowed-host NAME\n");
}

std::string plain_http_answer() {
  return closing_answer("400 Bad Request",
                        "this port speaks https only: open the dashboard as https://, not "
                        "http://\n");
}

bool origin_allowed(std::string_view origin, const AllowedHosts& allowed, Scheme scheme) {
  const std::string_view prefix = scheme == Scheme::kHttps ? "https://" : "http://";
  if (origin.substr(0, prefix.size()) != prefix) return false;
  return host_allowed(origin.substr(prefix.size()), allowed);
}

Result<std::string> parse_allowed_host(std::string_view name) {
  const bool word_chars = std::all_of(name.begin(), name.end(), [](unsigned char c) {
    return std::isalnum(c) || c == '-' || c == '.';
  });
  const bool has_letter =
      std::any_of(name.begin(), name.end(), [](unsigned char c) { return std::isalpha(c); });
  if (name.empty() || !word_chars || !has_letter || name.front() == '.' || name.back() == '.') {
    return Error{ErrorCode::kInvalidValue,
                 "--allowed-host '" + std::string(name) +
                     "': expected a host name like bench-pc or bench.example (no port, no "
                     "address: the addresses teejet-web listens on are allowed already)"};
  }
  return lower(name);
}

std::vector<std::string> local_addresses() {
  std::vector<std::string> addresses;
  ifaddrs* interfaces = nullptr;
  if (getifaddrs(&interfaces) != 0) return addresses;
  for (const ifaddrs* entry = interfaces; entry != nullptr; entry = entry->ifa_next) {
    if (entry->ifa_addr == nullptr) continue;
    const int family = entry->ifa_addr->sa_family;
    char text[INET6_ADDRSTRLEN];
    const void* bytes = nullptr;
    if (family == AF_INET) {
      bytes = &reinterpret_cast<const sockaddr_in*>(entry->ifa_addr)->sin_addr;
    } else if (family == AF_INET6) {
      bytes = &reinterpret_cast<const sockaddr_in6*>(entry->ifa_addr)->sin6_addr;
    } else {
      continue;
    }
    if (inet_ntop(family, bytes, text, sizeof text) != nullptr) addresses.emplace_back(text);
  }
  freeifaddrs(interfaces);
  return addresses;
}

}  // namespace teejet::web
