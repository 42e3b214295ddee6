#pragma once

// Who may open a page's WebSocket: the one rule the handshake asks, before it answers 101. No
// network here, so that the unit tests cover it whole.

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

#include "request_guard.hpp"

namespace teejet::web {

// At most this many pages at once: each costs a tick's JSON and an outbox. The 49th is refused
// (its page shows "reconnecting" and retries with its backoff).
inline constexpr std::size_t kMaxPages = 48;

// Why a page was not admitted: the HTTP status it is answered with and a reason for the body.
struct PageRefusal {
  unsigned status;
  std::string reason;
  bool operator==(const PageRefusal&) const = default;
};

// Nothing when the page may open, `open_pages` being the pages already admitted; its request's
// Host was allowed already, as every request's. A page of another site must not reach the bench
// through the operator's browser: a browser's Origin (nullopt when absent) must be a page of this
// server (origin_allowed). A client without Origin is not a browser, and no other site's script
// can make one.
std::optional<PageRefusal> refuse_page(std::optional<std::string_view> origin,
                                       const AllowedHosts& hosts, Scheme scheme,
                                       std::size_t open_pages);

}  // namespace teejet::web
