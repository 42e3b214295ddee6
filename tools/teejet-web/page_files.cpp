#include "page_files.hpp"

#include <array>
#include <fstream>
#include <iterator>
#include <system_error>
#include <utility>

namespace teejet::web {

std::string_view content_type(const std::filesystem::path& name) {
  static constexpr std::array<std::pair<std::string_view, std::string_view>, 8> kTypes{{
      {".html", "text/html; charset=utf-8"},
      {".css", "text/css; charset=utf-8"},
      {".js", "text/javascript; charset=utf-8"},
      {".json", "application/json"},
      {".svg", "image/svg+xml"},
      {".png", "image/png"},
      {".ico", "image/x-icon"},
      {".txt", "text/plain; charset=utf-8"},
  }};
  const std::string extension = name.extension().string();
  for (const auto& [known, type] : kTypes) {
    if (extension == known) return type;
  }
  return "application/octet-stream";
}

Result<PageFiles> PageFiles::load(const std::filesystem::path& www) {
  PageFiles files;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(www, error)) {
    if (!entry.is_regular_file(error)) continue;
    std::ifstream in(entry.path(), std::ios::binary);
    std::string body{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    if (!in && !in.eof()) {
      return Error{ErrorCode::kUnavailable, "cannot read " + entry.path().string()};
    }
    files.files_["/" + entry.path().filename().string()] = {std::string(content_type(entry.path())),
                                                            std::move(body)};
  }
  if (error) {
    return Error{ErrorCode::kUnavailable, "cannot read " + www.string() + ": " + error.message()};
  }
  return files;
}

const PageFile* PageFiles::find(std::string_view target) const {
  target = target.substr(0, target.find('?'));
  if (target == "/") target = "/index.html";
  const auto found = files_.find(target);
  return found == files_.end() ? nullptr : &found->second;
}

}  // namespace teejet::web
