#pragma once

// What teejet-web checks of every request before it answers, with no HTTP library in it, so
// that any transport calls the same code:
// - Host: only the addresses it listens on (and the names the operator allows). A page of
//   another site that rebinds its own name to 127.0.0.1 reaches the server with its own name in
//   Host, and is refused; with the Host check, Origin can be trusted to say which page it is.
// - Origin of a WebSocket: a page served by teejet-web itself (an allowed host), or none (not a
//   browser).
// - The headers every answer carries, so that no other site can frame the page.

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "teejet/core/result.hpp"

namespace teejet::web {

// Sent with every answer, errors and the WebSocket handshake included. The page has no inline
// script or style attribute and talks only to its own server.
struct Header {
  std::string_view name;
  std::string_view value;
};
inline constexpr std::array<Header, 4> kSecurityHeaders{{
    {"X-Frame-Options", "DENY"},
    {"Content-Security-Policy",
     "default-src 'self'; connect-src 'self'; frame-ancestors 'none'; base-uri 'none'; "
     "form-action 'none'; object-src 'none'"},
    {"X-Content-Type-Options", "nosniff"},
    {"Referrer-Policy", "no-referrer"},
}};

struct AllowedHosts {
  std::uint16_t port = 0;
  std::vector<std::string> addresses;  // literals in inet_ntop's form: "127.0.0.1", "::1"
  std::vector<std::string> names;      // lower case: "localhost", the --allowed-host names
};

// The hosts of a server listening on `listen` (as parse_listen() made it): its address, or, for
// 0.0.0.0 and [::], every address in `local_addresses`; "localhost" when that reaches it (a
// loopback or every-interface listen); and `names`.
AllowedHosts allowed_hosts(std::string_view listen, const std::vector<std::string>& local_addresses,
                           const std::vector<std::string>& names);

// Whether a server listening on `listen` (as parse_listen() made it) is reached from this machine
// only: a loopback address, where nothing it sends crosses a network.
bool loopback_listen(std::string_view listen);

// Whether a Host header ("127.0.0.1:8080", "[::1]:8080", "bench:8080", "bench" for port 80)
// names an allowed host on the served port.
bool host_allowed(std::string_view host, const AllowedHosts& allowed);

// The whole answer to a request with a Host not allowed: 403, the security headers, a reason,
// and the connection closed. Written as bytes, because CivetWeb leaves the status line out of
// its own error answer to a WebSocket handshake.
std::string forbidden_host_answer();

// The whole answer to a plain http request on a TLS server's port: 400 saying the port speaks
// https, the security headers, and the connection closed; never the page or data.
std::string plain_http_answer();

// How the server is reached: its pages' Origin has this scheme.
enum class Scheme { kHttp, kHttps };

// Whether a WebSocket's Origin is a page of this server: "http://" ("https://" for a TLS server)
// and an allowed host.
bool origin_allowed(std::string_view origin, const AllowedHosts& allowed, Scheme scheme);

// --allowed-host NAME: a DNS name as people type it (letters, digits, '-' and '.'), no port.
Result<std::string> parse_allowed_host(std::string_view name);

// The machine's own addresses now, for a server listening on every interface.
std::vector<std::string> local_addresses();

}  // namespace teejet::web
