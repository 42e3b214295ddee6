#include "page_admission.hpp"

namespace teejet::web {

std::optional<PageRefusal> refuse_page(std::optional<std::string_view> origin,
                                       const AllowedHosts& hosts, Scheme scheme,
                                       std::size_t open_pages) {
  if (origin && !origin_allowed(*origin, hosts, scheme)) {
    return PageRefusal{403, "a page of another origin may not open the dashboard's WebSocket"};
  }
  if (open_pages >= kMaxPages) {
    return PageRefusal{503, "already " + std::to_string(kMaxPages) + " pages open"};
  }
  return std::nullopt;
}

}  // namespace teejet::web
