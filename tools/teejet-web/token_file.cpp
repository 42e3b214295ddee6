#include "token_file.hpp"

#include <sys/stat.h>

#include <cstdio>
#include <fstream>
#include <iterator>

namespace teejet::web {

std::optional<std::string> owner_only_problem(const std::filesystem::path& path) {
  struct stat status {};
  if (::stat(path.c_str(), &status) != 0) return "cannot read it";
  if (!S_ISREG(status.st_mode)) return "not a regular file";
  if ((status.st_mode & (S_IRWXG | S_IRWXO)) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(status.st_mode & 07777));
    return std::string("group or others may access it (mode ") + mode + "): chmod 600 " +
           path.string();
  }
  return std::nullopt;
}

Result<std::string> read_token_file(const std::filesystem::path& path) {
  const auto fail = [&](const std::string& why) {
    return Error{ErrorCode::kInvalidValue, "--token-file " + path.string() + ": " + why};
  };
  if (const auto problem = owner_only_problem(path)) return fail(*problem);
  std::ifstream file(path, std::ios::binary);
  if (!file) return fail("cannot read it");
  std::string token((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (!token.empty() && token.back() == '\n') token.pop_back();
  if (!token.empty() && token.back() == '\r') token.pop_back();
  if (token.empty()) return fail("the token is empty");
  return token;
}

}  // namespace teejet::web
