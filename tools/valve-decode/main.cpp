// valve-decode: candump -L lines in, one JSON object per line out.

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>
#include <string_view>
#include <vector>

#include "frame_json.hpp"
#include "teejet/candump/log_line.hpp"
#include "teejet/codec/codec.hpp"
#include "teejet/command_line.hpp"

namespace {

constexpr std::string_view kStandardInput = "-";
constexpr int kExitUsage = 2;

constexpr const char* kDescription =
    "Decodes TeeJet CAN valve traffic from can-utils `candump -L` logs into JSON Lines.";

constexpr const char* kFooter = R"(Reads `candump -L` lines such as
  (1700000000.000123) can0 18EFD5D8#020384FFFFFFFFFF
from each FILE in turn, or from standard input when no FILE is given or FILE is "-",
and prints exactly one JSON object per line:
  {"t":1700000000.000123,"iface":"can0","dir":"from_valve","addr":216,"msg":"position","fields":{"degrees":90.0}}

  t       the timestamp with the logged digits (leading zeros of the seconds dropped, as JSON requires)
  iface   the CAN interface
  dir     "to_valve" (controller 0xD5 to valve) or "from_valve" (valve to controller)
  addr    the valve's address, 216..247 (0xD8..0xF7), whichever way the frame goes
  msg     the message name, e.g. "target_degrees", "i_am_here"
  fields  the message's values in engineering units, {} when it has none

A line that cannot be parsed or decoded prints
  {"error":"<reason>","line":"<the line>"}
and decoding goes on. Blank lines are skipped: candump never writes them.
Output is flushed after every line read from standard input, so that
`candump -L can0 | valve-decode` is live.

Exit status: 0, also when some lines did not decode; 1 when a FILE or standard input could
not be read (the other FILEs are still decoded) or the output could not be written; 2 for a
bad command line.)";

// Returns 0 at the end of the input, or the errno of the read that failed.
int decode_stream(std::istream& input, std::FILE* c_stream, bool flush_each_line) {
  errno = 0;
  std::string line;
  while (std::getline(input, line)) {
    std::string_view text = line;
    if (text.ends_with('\r')) text.remove_suffix(1);  // CRLF logs from Windows tools
    if (teejet::valve_decode::is_blank_line(text)) continue;
    std::cout << teejet::valve_decode::decode_log_line(text) << '\n';
    // Live pipes (`candump -L can0 | valve-decode`) must see each frame at once. cin's tie to
    // cout happens to flush too, but that is easy to lose when tuning stream settings.
    if (flush_each_line) std::cout.flush();
  }
  // std::cin reads through stdio, which ends a failed read (a directory, a closed descriptor)
  // like the end of the input, without setting badbit: only the FILE knows it was an error.
  const bool failed = input.bad() || (c_stream != nullptr && std::ferror(c_stream) != 0);
  if (!failed) return 0;
  return errno != 0 ? errno : EIO;
}

// Returns false, after saying why on stderr, when the file could not be read to the end.
bool decode_file(const std::string& path) {
  if (path == kStandardInput) {
    const int error = decode_stream(std::cin, stdin, /*flush_each_line=*/true);
    if (error == 0) return true;
    std::cerr << "valve-decode: error reading standard input: " << std::strerror(error) << '\n';
    return false;
  }
  errno = 0;
  std::ifstream input(path);
  if (!input) {
    std::cerr << "valve-decode: cannot open '" << path << "': " << std::strerror(errno) << '\n';
    return false;
  }
  const int error = decode_stream(input, nullptr, /*flush_each_line=*/false);
  if (error == 0) return true;
  std::cerr << "valve-decode: error reading '" << path << "': " << std::strerror(error) << '\n';
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{kDescription, "valve-decode"};
  app.footer(kFooter);
  app.set_version_flag("--version", "valve-decode " TEEJET_VERSION);
  std::vector<std::string> paths;
  app.add_option("FILE", paths, "candump -L log files; none or \"-\" reads standard input")
      ->type_name("");
  if (const auto exit_status = teejet::command_line::parse(app, argc, argv, kExitUsage)) {
    return *exit_status;
  }

  if (paths.empty()) paths.emplace_back(kStandardInput);
  bool all_read = true;
  for (const auto& path : paths) all_read = decode_file(path) && all_read;

  std::cout.flush();
  if (!std::cout) {
    std::cerr << "valve-decode: error writing the output\n";
    return 1;
  }
  return all_read ? 0 : 1;
}
