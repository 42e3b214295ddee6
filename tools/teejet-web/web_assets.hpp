#pragma once

// Where teejet-web finds its page (index.html, dashboard.js, ...): --www DIR when given, else
// next to the executable (the build tree, where the build copies them), else the install tree's
// <prefix>/share/teejet-web/www relative to <prefix>/bin, so an installed copy is relocatable.

#include <filesystem>
#include <string_view>
#include <vector>

#include "teejet/core/result.hpp"

namespace teejet::web {

// The directories tried, in order: only `explicit_dir` when it is not empty.
std::vector<std::filesystem::path> www_candidates(std::string_view explicit_dir,
                                                  const std::filesystem::path& exe_dir);

// The first candidate holding index.html, or an Error naming every path tried.
Result<std::filesystem::path> find_www(std::string_view explicit_dir,
                                       const std::filesystem::path& exe_dir);

}  // namespace teejet::web
