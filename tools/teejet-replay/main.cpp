// teejet-replay: publishes a teejet-record recording back into a DDS domain with its original
// timing, so that an ECU or a test bench can be developed against a recorded run without valves.

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <iostream>

#include "replayer.hpp"
#include "teejet/command_line.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/stop_signals.hpp"

namespace {

constexpr int kExitUsage = 2;
// A year into a recording: far beyond any recording, and well within the clocks' range.
constexpr double kMaxOffsetSeconds = 365.0 * 86400.0;
// As valvectl's waits: an hour.
constexpr double kMaxWaitSeconds = 3600.0;

constexpr const char* kFooter = R"(Examples:
  teejet-replay run.mcap                                 as recorded
  teejet-replay run.mcap --rate 4 --loop                 four times as fast, over and over
  teejet-replay run.mcap --topic 'teejet/valve/position' --start 30 --end 90

Messages go out in file order, spaced as they were received (log time) divided by --rate, each
with its recorded source timestamp (the CAN receive time). Disposals are replayed as disposals.
Recorded commands (teejet/valve/command) are not published unless --with-commands is given:
a gateway in the domain would move its valves. Nothing is published where a gateway the
recording holds is live (its state and the recorded one would mix) unless --into-live-gateways
is given: replay into a domain of its own (--domain). Raw frames (teejet/can/frame) are
published as DDS samples; to put frames back on a CAN bus, write them as candump -L text
(teejet-record --candump) and use can-utils' canplayer.

Exit status: 0 when done or after SIGINT/SIGTERM; 1 for a file that cannot be read, a channel of
a type this program does not know, a window with nothing in it, a live gateway of the recording,
or DDS failing; 2 for a bad command line.)";

std::atomic<bool> stop_requested{false};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Publishes a teejet-record recording back into a DDS domain with its timing.",
               "teejet-replay"};
  app.footer(kFooter);
  app.set_version_flag("--version", "teejet-replay " TEEJET_VERSION);
  teejet::replay::ReplayOptions options;
  double start_s = 0, end_s = -1, wait_s = 1;
  bool quiet = false;
  app.add_option("FILE", options.file, "an MCAP recording made by teejet-record")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--rate", options.rate, "speed factor: 2 is twice as fast")
      ->capture_default_str()
      ->check(teejet::command_line::finite_range(0.001, 1000.0));
  app.add_flag("--loop", options.loop, "start again at the end, until Ctrl-C");
  app.add_option("--topic", options.topics, "replay only topics matching GLOB (repeatable)")
      ->type_name("GLOB");
  app.add_flag("--with-commands", options.with_commands,
               "also publish recorded commands (they move the valves of a gateway in the domain)");
  app.add_flag("--into-live-gateways", options.into_live_gateways,
               "publish even where a gateway of the recording is live (their states mix)");
  app.add_option("--start", start_s, "begin this many seconds into the recording")
      ->check(teejet::command_line::finite_range(0.0, kMaxOffsetSeconds));
  app.add_option("--end", end_s, "end this many seconds into the recording")
      ->check(teejet::command_line::finite_range(0.0, kMaxOffsetSeconds));
  app.add_option("--wait-for-readers", wait_s,
                 "seconds to wait, before the first message, for a reader on every topic")
      ->capture_default_str()
      ->check(teejet::command_line::finite_range(0.0, kMaxWaitSeconds));
  app.add_option("--domain", options.domain, "DDS domain")
      ->capture_default_str()
      ->check(CLI::Range(0, teejet::dds::kMaxDomain));
  app.add_option("--profile", options.profile_file, "Fast DDS XML profiles file")
      ->check(CLI::ExistingFile);
  app.add_flag("-q,--quiet", quiet, "no summary");
  teejet::command_line::refuse_empty_values(app);
  if (const auto exit_status = teejet::command_line::parse(app, argc, argv, kExitUsage)) {
    return *exit_status;
  }
  if (end_s >= 0 && end_s < start_s) {
    std::cerr << "teejet-replay: --end " << end_s << " is before --start " << start_s << '\n';
    return kExitUsage;
  }
  options.start = teejet::seconds(start_s);
  if (end_s >= 0) options.end = teejet::seconds(end_s);
  options.wait_for_readers = teejet::seconds(wait_s);

  teejet::command_line::stop_on_sigint_or_sigterm(stop_requested);

  auto replayed = teejet::replay::replay(options, stop_requested);
  if (!replayed) {
    std::cerr << "teejet-replay: " << replayed.error().reason << '\n';
    return 1;
  }
  if (!quiet) {
    std::cerr << fmt::format(
        "teejet-replay: {} messages published ({} refused), {} pass(es); {} went out over 1 ms "
        "late, the latest {:.3f} ms (message {})\n",
        replayed->published, replayed->failed, replayed->loops, replayed->late_over_1ms,
        std::chrono::duration<double, std::milli>(replayed->worst_lateness).count(),
        replayed->worst_index);
    for (const auto& [topic, count] : replayed->per_topic) {
      std::cerr << fmt::format("  {:<36} {:>9}\n", topic, count);
    }
    if (replayed->failed > 0) std::cerr << "  last refused: " << replayed->last_failure << '\n';
  }
  return 0;
}
