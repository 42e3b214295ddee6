#pragma once

// teejet-record --info FILE: what a recording holds, as read through from its first record; its
// summary, when it has one, is held against that.

#include <ostream>
#include <string>

#include "teejet/mcap/reader.hpp"

namespace teejet::record {

// Exit status: 0 for a readable file (also one that ends early: a killed recorder's; it says
// so), 1 for one that cannot be read or is damaged (the reason on `err`).
int print_info(const std::string& path, bool json, std::ostream& out, std::ostream& err);
// The same for bytes from elsewhere (the fuzzer's), shown under the name `path`.
int print_info(mcap::Source& file, const std::string& path, bool json, std::ostream& out,
               std::ostream& err);

}  // namespace teejet::record
