#pragma once

// The page's files (index.html, dashboard.js, ...), read once at start from the directory
// find_www() found and served from memory: a request names a key of this fixed map or gets 404,
// so no path a client sends ever reaches the file system.

#include <filesystem>
#include <map>
#include <string>
#include <string_view>

#include "teejet/core/result.hpp"

namespace teejet::web {

struct PageFile {
  std::string content_type;
  std::string body;
};

class PageFiles {
 public:
  // Every regular file directly in `www` (the page has no subdirectories), served as
  // "/<name>"; "/" serves index.html. An Error when the directory or a file cannot be read.
  static Result<PageFiles> load(const std::filesystem::path& www);

  // The file a request target names (its query, "?...", ignored), or nullptr.
  const PageFile* find(std::string_view target) const;

 private:
  std::map<std::string, PageFile, std::less<>> files_;  // by "/<name>"
};

// By the name's extension; application/octet-stream for any other.
std::string_view content_type(const std::filesystem::path& name);

}  // namespace teejet::web
