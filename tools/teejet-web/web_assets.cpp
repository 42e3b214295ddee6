#include "web_assets.hpp"

#include <system_error>

namespace teejet::web {

std::vector<std::filesystem::path> www_candidates(std::string_view explicit_dir,
                                                  const std::filesystem::path& exe_dir) {
  if (!explicit_dir.empty()) return {std::filesystem::path(explicit_dir)};
  return {exe_dir / "www", (exe_dir / ".." / "share" / "teejet-web" / "www").lexically_normal()};
}

Result<std::filesystem::path> find_www(std::string_view explicit_dir,
                                       const std::filesystem::path& exe_dir) {
  std::string tried;
  for (const auto& candidate : www_candidates(explicit_dir, exe_dir)) {
    std::error_code error;
    if (std::filesystem::is_regular_file(candidate / "index.html", error)) return candidate;
    tried += (tried.empty() ? "" : ", ") + candidate.string();
  }
  return Error{ErrorCode::kUnavailable,
               "no dashboard page (index.html) in " + tried +
                   (explicit_dir.empty() ? " (give its directory with --www DIR)" : "")};
}

}  // namespace teejet::web
