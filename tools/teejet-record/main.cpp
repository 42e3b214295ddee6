// teejet-record: every teejet DDS topic (and the raw bus, when a gateway publishes it) into an
// MCAP file that Foxglove, Lichtblick and PlotJuggler open; --info says what a recording holds.

#include <fmt/format.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <array>
#include <atomic>
#include <csignal>
#include <cstdlib>
#include <iostream>

#include "info.hpp"
#include "recorder.hpp"
#include "teejet/command_line.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/stop_signals.hpp"

namespace {

// 30 days: longer runs end by Ctrl-C or the service manager, not by a deadline.
constexpr double kMaxDurationSeconds = 30.0 * 86400.0;
constexpr int kExitUsage = 2;
// Fast DDS's event thread stopped (docs/topics.md, "A participant that stops"): the file is
// finished; a supervisor starts a new recording.
constexpr int kExitDdsStalled = 3;

constexpr const char* kFooter = R"(Examples:
  teejet-record -o run.mcap                          every teejet topic until Ctrl-C
  teejet-record -o run.mcap --duration 60 --topic 'teejet/valve/position' --topic 'teejet/can/*'
  teejet-record -o run.mcap --max-size 100M          run_000.mcap, run_001.mcap, ...
  teejet-record -o run.mcap --candump run.log        the raw frames also as candump -L text
  teejet-record --info run.mcap

One channel per topic, schema teejet::<Type> (encoding omgidl: the text of valve.idl), messages
as the CDR payload they had on the wire; log time = when received, publish time = the sample's
source timestamp (the CAN receive time). Disposals (Clear Errors) go to "<topic>/disposed".
Raw frames (teejet/can/frame) exist only when the gateway runs with --record-frames.
Chunks are closed at least once a second: a recorder that is killed loses at most that.
docs/recording.md has the details.

Exit status: 0 after --duration, SIGINT or SIGTERM (the file is complete); 1 when DDS or the file
failed (the file is still finished when possible); 2 for a bad command line.
--info: 0 for a readable file (a killed recorder's too, with a warning), 1 for a damaged one.)";

// "100M" -> 100 * 2^20. Accepts K, M, G (powers of 1024) and plain bytes.
std::string parse_size(const std::string& text, std::uint64_t& bytes) {
  std::size_t used = 0;
  unsigned long long number = 0;
  try {
    number = std::stoull(text, &used);
  } catch (const std::exception&) {
    return "'" + text + "' is not a size (bytes, or a number with K, M or G)";
  }
  const std::string unit = text.substr(used);
  std::uint64_t scale = 1;
  if (unit == "K" || unit == "k")
    scale = 1ull << 10;
  else if (unit == "M" || unit == "m")
    scale = 1ull << 20;
  else if (unit == "G" || unit == "g")
    scale = 1ull << 30;
  else if (!unit.empty())
    return "'" + text + "': unknown unit '" + unit + "' (K, M or G)";
  bytes = number * scale;
  return {};
}

std::string human_bytes(std::uint64_t bytes) {
  if (bytes >= (1ull << 20))
    return fmt::format("{:.1f} MiB", static_cast<double>(bytes) / (1 << 20));
  if (bytes >= (1ull << 10))
    return fmt::format("{:.1f} KiB", static_cast<double>(bytes) / (1 << 10));
  return fmt::format("{} B", bytes);
}

std::string short_topic(const std::string& topic) {
  const auto slash = topic.rfind('/');
  if (topic.ends_with("/disposed")) {
    const auto before = topic.rfind('/', slash - 1);
    return topic.substr(before + 1);
  }
  return slash == std::string::npos ? topic : topic.substr(slash + 1);
}

// One line, rewritten in place about once a second: elapsed time, totals, and the rate of each
// topic since the last line, busiest first.
class ProgressLine {
 public:
  void show(const teejet::record::Progress& progress) {
    const double seconds = std::chrono::duration<double>(progress.elapsed).count();
    const double interval = std::max(seconds - last_seconds_, 1e-3);
    std::vector<std::pair<double, std::string>> rates;
    for (const auto& [topic, tally] : progress.topics) {
      const double rate = static_cast<double>(tally.messages - last_[topic]) / interval;
      if (rate > 0) rates.emplace_back(rate, short_topic(topic));
      last_[topic] = tally.messages;
    }
    std::sort(rates.rbegin(), rates.rend());
    const auto total = static_cast<long>(seconds);
    std::string line =
        fmt::format("{:02}:{:02}:{:02}  {} msgs  {}  {}", total / 3600, total / 60 % 60, total % 60,
                    progress.messages, human_bytes(progress.file_bytes),
                    progress.files.empty() ? std::string() : progress.files.back());
    for (const auto& [rate, topic] : rates) line += fmt::format("  {} {:.0f}/s", topic, rate);
    winsize size{};
    const std::size_t width =
        ::ioctl(STDERR_FILENO, TIOCGWINSZ, &size) == 0 && size.ws_col > 0 ? size.ws_col : 120;
    if (line.size() >= width) line.resize(width - 1);
    std::cerr << "\r\033[K" << line << std::flush;
    last_seconds_ = seconds;
  }

 private:
  double last_seconds_ = 0;
  std::map<std::string, std::uint64_t> last_;
};

void print_summary(const teejet::record::Progress& progress) {
  const double seconds = std::chrono::duration<double>(progress.elapsed).count();
  std::cerr << fmt::format("teejet-record: {} messages in {:.1f} s, {} in", progress.messages,
                           seconds, human_bytes(progress.file_bytes));
  for (const auto& file : progress.files) std::cerr << ' ' << file;
  std::cerr << '\n';
  for (const auto& [topic, tally] : progress.topics) {
    std::cerr << fmt::format("  {:<36} {:>9} messages  {:>10}\n", topic, tally.messages,
                             human_bytes(tally.bytes));
  }
  if (progress.unknown_disposals > 0) {
    std::cerr << fmt::format(
        "  {} disposal(s) of instances never seen alive could not be recorded\n",
        progress.unknown_disposals);
  }
  if (progress.frames_without_candump_line > 0) {
    std::cerr << fmt::format(
        "  {} frame(s) have no candump -L form (more than 8 bytes, a bad interface name): in "
        "the MCAP file only\n",
        progress.frames_without_candump_line);
  }
}

std::atomic<bool> stop_requested{false};

}  // namespace

int main(int argc, char** argv) {
  std::signal(SIGPIPE, SIG_IGN);
  CLI::App app{"Records the teejet DDS topics (and the raw CAN frames) to an MCAP file.",
               "teejet-record"};
  app.footer(kFooter);
  app.set_version_flag("--version", "teejet-record " TEEJET_VERSION);
  teejet::record::RecorderOptions options;
  std::string info_path, max_size_text, chunk_size_text, compression = "zstd";
  double duration_seconds = 0;
  bool json = false, progress_flag = false, quiet = false;
  auto* output =
      app.add_option("-o,--output", options.output, "the MCAP file to write")->type_name("FILE");
  auto* info = app.add_option("--info", info_path, "print what a recording holds, and exit")
                   ->type_name("FILE")
                   ->excludes(output);
  app.add_flag("--json", json, "with --info: one JSON object")->needs(info);
  app.add_option("--topic", options.topics,
                 "record only topics matching GLOB (repeatable; default every teejet topic)")
      ->type_name("GLOB");
  app.add_option("--duration", duration_seconds, "stop after this many seconds (default: Ctrl-C)")
      ->check(teejet::command_line::finite_range(0.001, kMaxDurationSeconds));
  app.add_option("--max-size", max_size_text,
                 "start a new file when one reaches SIZE (K, M, G); files get _000, _001, ...")
      ->type_name("SIZE");
  app.add_option("--compression", compression, "chunk compression")
      ->check(CLI::IsMember({"zstd", "lz4", "none"}))
      ->capture_default_str();
  app.add_option("--chunk-size", chunk_size_text, "close a chunk at this many bytes (default 1M)")
      ->type_name("SIZE");
  app.add_option("--candump", options.candump_path,
                 "also write teejet/can/frame as candump -L text (canplayer, python-can)")
      ->type_name("FILE");
  app.add_option("--domain", options.domain, "DDS domain")
      ->capture_default_str()
      ->check(CLI::Range(0, teejet::dds::kMaxDomain));
  app.add_option("--profile", options.profile_file, "Fast DDS XML profiles file, as the gateway's")
      ->check(CLI::ExistingFile);
  app.add_flag("--progress", progress_flag,
               "show the progress line also when stderr is no terminal");
  app.add_flag("-q,--quiet", quiet, "no progress line and no summary");
  teejet::command_line::refuse_empty_values(app);
  if (const auto exit_status = teejet::command_line::parse(app, argc, argv, kExitUsage)) {
    return *exit_status;
  }
  if (!info_path.empty()) return teejet::record::print_info(info_path, json, std::cout, std::cerr);
  if (options.output.empty()) {
    std::cerr << "teejet-record: give -o FILE to record, or --info FILE\n"
                 "Run teejet-record --help for more information.\n";
    return kExitUsage;
  }
  if (!max_size_text.empty()) {
    if (const auto error = parse_size(max_size_text, options.max_size); !error.empty()) {
      std::cerr << "teejet-record: --max-size " << error << '\n';
      return kExitUsage;
    }
  }
  // Each file carries its schemas (the IDL text, about 10 KB per topic) and a summary: a
  // smaller limit would make files of little else.
  constexpr std::uint64_t kSmallestSplit = 1ull << 20;
  if (options.max_size != 0 && options.max_size < kSmallestSplit) {
    std::cerr << "teejet-record: --max-size " << max_size_text
              << " is below 1M: each file carries about 10 KB of schema per topic\n";
    return kExitUsage;
  }
  if (!chunk_size_text.empty()) {
    std::uint64_t chunk = 0;
    if (const auto error = parse_size(chunk_size_text, chunk); !error.empty() || chunk == 0) {
      std::cerr << "teejet-record: --chunk-size " << (error.empty() ? "must be above 0" : error)
                << '\n';
      return kExitUsage;
    }
    options.chunk_size = chunk;
  }
  if (auto selected = teejet::record::select_topics(options.topics); !selected) {
    std::cerr << "teejet-record: " << selected.error().reason << '\n';
    return kExitUsage;
  }
  options.compression = compression == "none" ? "" : compression;
  if (duration_seconds > 0) options.duration = teejet::seconds(duration_seconds);

  teejet::command_line::stop_on_sigint_or_sigterm(stop_requested);

  const bool show_progress = !quiet && (progress_flag || ::isatty(STDERR_FILENO) == 1);
  ProgressLine line;
  bool shown = false;
  std::uint64_t rejoins_said = 0;
  auto recorded = teejet::record::record(
      options, stop_requested,
      [&](const teejet::record::Progress& progress) {
        if (progress.rejoins > rejoins_said && !quiet) {
          std::cerr << (shown ? "\n" : "") << "teejet-record: met no gateway over TCP; joined DDS "
                    << "domain " << options.domain << " again (" << progress.rejoins
                    << " time(s))\n";
          rejoins_said = progress.rejoins;
        }
        if (!show_progress) return;
        line.show(progress);
        shown = true;
      },
      [&] {
        if (!quiet) {
          std::cerr << "teejet-record: recording to " << options.output << " in DDS domain "
                    << options.domain << '\n';
        }
      });
  if (shown) std::cerr << '\n';
  if (!recorded) {
    std::cerr << "teejet-record: " << recorded.error().reason << '\n';
    // The stuck participant is still there, and the exit's destructors would wait for it.
    if (recorded.error().code == teejet::ErrorCode::kStalled) std::_Exit(kExitDdsStalled);
    return 1;
  }
  if (!quiet) print_summary(*recorded);
  return 0;
}
