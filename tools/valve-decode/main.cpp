// valve-decode: candump -L lines or an MCAP recording's frames in, one JSON object per frame out.

#include <CLI/CLI.hpp>
#include <array>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>
#include <string_view>
#include <vector>

#include "mcap_input.hpp"
#include "teejet/candump/log_line.hpp"
#include "teejet/codec/codec.hpp"
#include "teejet/command_line.hpp"
#include "teejet/frame_json/frame_json.hpp"

namespace {

constexpr std::string_view kStandardInput = "-";
constexpr int kExitUsage = 2;

constexpr const char* kDescription =
    "Decodes TeeJet CAN valve traffic from can-utils `candump -L` logs or MCAP recordings "
    "into JSON Lines.";

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

MCAP recordings (teejet-record, with teejet-gateway --record-frames): a FILE that begins with
the MCAP magic bytes is read as one, with no option needed; standard input is always candump
text, and so is a FILE with any other first bytes (a damaged magic too: its lines print as
errors). Every message of every channel whose schema is teejet::BusFrame (topic
teejet/can/frame) prints, in file order, exactly the line of the same frame logged by
candump -L: "t" is the frame's stamp_ns cut to microseconds, "iface" its can_interface.
Other channels are skipped. Only when a file's frames come from more than one gateway does
each frame's line (decoded or not) carry the gateway's name after "t" (or "error"):
  {"t":1700000000.000123,"gw":"sprayer-left","iface":"can0",...}
A message that is not a frame (does not deserialize, dlc above 8, data not dlc bytes) prints
  {"error":"<reason>","topic":"teejet/can/frame","sequence":<n>,"log_time":<ns>}
and decoding goes on. A recording without a frame channel or a damaged one (bad CRC, a record
that does not parse) is an error naming the file, and prints nothing of it; a recording that
ends early (the recorder was killed) is decoded up to there with a warning on standard error.

Exit status: 0, also when some lines did not decode or a recording ended early; 1 when a FILE
or standard input could not be read, a recording is damaged or has no frame channel (the other
FILEs are still decoded), or the output could not be written; 2 for a bad command line.)";

void decode_line(std::string_view text, bool flush) {
  if (text.ends_with('\r')) text.remove_suffix(1);  // CRLF logs from Windows tools
  if (teejet::frame_json::is_blank_line(text)) return;
  std::cout << teejet::frame_json::decode_log_line(text) << '\n';
  // Live pipes (`candump -L can0 | valve-decode`) must see each frame at once. cin's tie to
  // cout happens to flush too, but that is easy to lose when tuning stream settings.
  if (flush) std::cout.flush();
}

// Returns 0 at the end of the input, or the errno of the read that failed.
int decode_stream(std::istream& input, std::FILE* c_stream, bool flush_each_line) {
  errno = 0;
  std::string line;
  while (std::getline(input, line)) decode_line(line, flush_each_line);
  // std::cin reads through stdio, which ends a failed read (a directory, a closed descriptor)
  // like the end of the input, without setting badbit: only the FILE knows it was an error.
  const bool failed = input.bad() || (c_stream != nullptr && std::ferror(c_stream) != 0);
  if (!failed) return 0;
  return errno != 0 ? errno : EIO;
}

// The rest of an MCAP stream whose magic has been read (a pipe, which can be read only once): in
// memory.
bool decode_mcap_rest(std::istream& input, const std::string& path) {
  std::vector<std::uint8_t> file(teejet::valve_decode::kMcapFirstLine.begin(),
                                 teejet::valve_decode::kMcapFirstLine.end());
  file.push_back('\n');
  errno = 0;
  std::array<char, 1 << 16> buffer{};
  while (input.read(buffer.data(), buffer.size()) || input.gcount() > 0) {
    file.insert(file.end(), buffer.data(), buffer.data() + input.gcount());
  }
  if (input.bad()) {
    std::cerr << "valve-decode: error reading '" << path
              << "': " << std::strerror(errno != 0 ? errno : EIO) << '\n';
    return false;
  }
  return teejet::valve_decode::decode_mcap(file, path, std::cout, std::cerr);
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
  std::ifstream input(path, std::ios::binary);
  if (!input) {
    std::cerr << "valve-decode: cannot open '" << path << "': " << std::strerror(errno) << '\n';
    return false;
  }
  std::string first_line;
  int error = 0;
  if (std::getline(input, first_line)) {
    // eof: the 7 bytes without the magic's newline are not an MCAP file.
    if (first_line == teejet::valve_decode::kMcapFirstLine && !input.eof()) {
      // A regular file is read record by record; a pipe (valve-decode <(...)) only once, whole.
      auto file = teejet::mcap::FileSource::open(path);
      if (!file) return decode_mcap_rest(input, path);
      return teejet::valve_decode::decode_mcap(**file, path, std::cout, std::cerr);
    }
    decode_line(first_line, /*flush=*/false);
    error = decode_stream(input, nullptr, /*flush_each_line=*/false);
  } else if (input.bad()) {
    error = errno != 0 ? errno : EIO;
  }
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
  app.add_option("FILE", paths,
                 "candump -L logs or MCAP recordings; none or \"-\" reads standard input "
                 "(candump text only)")
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
