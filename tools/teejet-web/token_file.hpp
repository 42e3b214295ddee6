#pragma once

// --token-file FILE: the command token out of the command line (which every local user reads in
// /proc/PID/cmdline), from a file only its owner may read. --tls-key's file is held to the same.

#include <filesystem>
#include <optional>
#include <string>

#include "teejet/core/result.hpp"

namespace teejet::web {

// Nothing when `path` is a regular file that group and others have no access to; otherwise why
// not, as a reason to print after the option and the file's name.
std::optional<std::string> owner_only_problem(const std::filesystem::path& path);

// The token in `path`, its trailing newline stripped; an Error when the file is not a regular
// file, group or others have any access to it, it cannot be read, or the token is empty.
Result<std::string> read_token_file(const std::filesystem::path& path);

}  // namespace teejet::web
