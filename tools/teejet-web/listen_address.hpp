#pragma once

// --listen ADDR:PORT, checked before the server starts: an IPv4 address or [IPv6] and a port.
// No default to all interfaces: 0.0.0.0 or [::] only when the operator types it.

#include <string>
#include <string_view>

#include "teejet/core/result.hpp"

namespace teejet::web {

inline constexpr const char* kDefaultListen = "127.0.0.1:8080";

// "ADDRESS:PORT" with the address a literal ("127.0.0.1:8080", "[::1]:8080"), or an Error naming
// `option` and what is wrong with `text` (a missing port shown with `example`).
Result<std::string> parse_listen(std::string_view text, std::string_view option = "--listen",
                                 std::string_view example = kDefaultListen);

}  // namespace teejet::web
