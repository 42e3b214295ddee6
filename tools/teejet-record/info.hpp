#pragma once

// teejet-record --info FILE: what a recording holds, from its summary when it has one (no
// message is read then), else by reading it through.

#include <ostream>
#include <string>

namespace teejet::record {

// Exit status: 0 for a readable file (also one that ends early: a killed recorder's; it says
// so), 1 for one that cannot be read or is damaged (the reason on `err`).
int print_info(const std::string& path, bool json, std::ostream& out, std::ostream& err);

}  // namespace teejet::record
