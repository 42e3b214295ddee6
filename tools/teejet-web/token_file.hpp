#pragma once

// --token-file FILE: the command token out of the command line (which every local user reads in
// /proc/PID/cmdline), from a file only its owner may read.

#include <filesystem>
#include <string>

#include "teejet/core/result.hpp"

namespace teejet::web {

// The token in `path`, its trailing newline stripped; an Error when the file is not a regular
// file, group or others have any access to it, it cannot be read, or the token is empty.
Result<std::string> read_token_file(const std::filesystem::path& path);

}  // namespace teejet::web
