#include "cli.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include "exit_codes.hpp"
#include "teejet/client/command_check.hpp"
#include "teejet/codec/table.hpp"
#include "teejet/command_line.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/layout/layout.hpp"

namespace teejet::valvectl {

using namespace client;

namespace {

constexpr const char* kDescription =
    "Lists, watches and commands TeeJet CAN valves through teejet-gateway over DDS.";

constexpr const char* kFooter =
    R"(A SERIAL is TJV123456 or 123456. A VALVE is a SERIAL, or the location the
valve sits at in its gateway's layout (section-03).

Exit status: 0 done; 2 no gateway, or no gateway knows the valve; 3 the gateway rejected the
command; 4 the command timed out, or no status arrived in time; 5 a newer command superseded it;
64 invalid arguments (nothing was sent); 1 anything else (DDS could not be set up, ...).
See docs/valvectl.md.)";

// Everything any subcommand can take, as typed; checked by the codec in build_invocation().
// Unsigned where the wire is: CLI11 refuses a negative number or one that does not fit.
struct RawArguments {
  std::string serial;
  std::string location;
  bool move = false;
  std::string what;
  double degrees = 0.0;
  unsigned speed = 100;
  std::string direction = "open";
  unsigned milliseconds = 0;
  unsigned every_tenths = 0;
  std::uint32_t bit_rate = 0;
  bool all = false;
  std::string gateway;
  bool baud_request = false;
  bool wait = false;
  bool progress = false;
  double wait_timeout_seconds = 60.0;
  double timeout_seconds = 5.0;
  int interval_ms = 1000;
  double duration_seconds = 0.0;
};

// The subcommands and their options, kept so build_invocation() can ask which were given.
struct Parser {
  CLI::App app{kDescription, "valvectl"};
  RawArguments raw;
  Invocation invocation;
  CLI::App* list = nullptr;
  CLI::App* watch = nullptr;
  CLI::App* layout = nullptr;
  CLI::App* neighbours = nullptr;
  CLI::App* assign = nullptr;
  CLI::App* identify = nullptr;
  CLI::App* unassign = nullptr;
  CLI::App* move = nullptr;
  CLI::App* stop = nullptr;
  CLI::App* manual = nullptr;
  CLI::App* jog = nullptr;
  CLI::App* clear_errors = nullptr;
  CLI::App* request = nullptr;
  CLI::App* baud = nullptr;
  CLI::Option* duration = nullptr;
  CLI::Option* wait_timeout = nullptr;  // of the subcommand that was used; see add_wait()
  CLI::Option* bit_rate = nullptr;
};

[[noreturn]] void usage_error(const std::string& message) { throw CLI::ValidationError(message); }

// What `request` asks for, as the codec names it (older words are accepted too: run-time, dps).
std::string telemetry_words() {
  std::string words;
  for (const std::string_view name : codec::telemetry_names()) {
    if (!words.empty()) words += ' ';
    words += name;
  }
  return words;
}

// Durations are whole milliseconds, at least one and at most `max_seconds`: an hour for the
// waits, a day for a watch. Beyond that a deadline is no longer a deadline, and far beyond it
// (1e10 s) the steady clock overflows and the wait ends at once.
constexpr double kMaxWaitSeconds = 3600.0;
constexpr double kMaxWatchSeconds = 86400.0;

std::chrono::milliseconds seconds_option(const char* option, double seconds, double max_seconds) {
  const double milliseconds = std::round(seconds * 1000.0);
  if (!std::isfinite(seconds) || milliseconds < 1.0 || seconds > max_seconds) {
    std::ostringstream message;
    message << option << ' ' << seconds << " is not a number of seconds from 0.001 to "
            << max_seconds;
    usage_error(message.str());
  }
  return std::chrono::milliseconds(static_cast<long long>(milliseconds));
}

// CLI11 makes 0 of an empty value (`--to ""` would move the valve to 0 degrees) and reads
// integers as C does: "-1" wraps around, "010" is 8 and "0x10" 16. A whole-number option takes
// decimal digits only; every option refuses an empty value.
const CLI::Validator kWholeNumber(
    [](std::string& value) -> std::string {
      if (value.empty()) return "the value is empty";
      if (value.find_first_not_of("0123456789") != std::string::npos) {
        return "'" + value + "' is not a whole number";
      }
      // CLI11 would read a leading 0 as octal.
      value.erase(0, std::min(value.find_first_not_of('0'), value.size() - 1));
      return "";
    },
    "", "WHOLE_NUMBER");

void add_serial(CLI::App* subcommand, RawArguments& raw, bool required = true) {
  subcommand->add_option("SERIAL", raw.serial, "the valve, TJV123456 or 123456")
      ->required(required);
}

// SERIAL, or the name of the place the valve sits at in its gateway's layout.
void add_valve(CLI::App* subcommand, RawArguments& raw, bool required = true) {
  subcommand
      ->add_option("VALVE", raw.serial,
                   "the valve: its serial (TJV123456 or 123456) or its location (section-03)")
      ->required(required);
}

// SERIAL, or --all [--gateway NAME]: what a person does to a whole boom.
void add_serial_or_all(CLI::App* subcommand, RawArguments& raw) {
  add_valve(subcommand, raw, /*required=*/false);
  subcommand->add_flag("--all", raw.all, "every online valve of every gateway, one command each");
  subcommand->add_option("--gateway", raw.gateway,
                         "with --all: only the valves of the gateway of this name (one boom)");
}

void add_wait(Parser& parser, CLI::App* subcommand, const char* what) {
  subcommand->add_flag("--wait", parser.raw.wait, what);
  subcommand
      ->add_option("--wait-timeout", parser.raw.wait_timeout_seconds,
                   "with --wait: give up after this many seconds without a final status")
      ->capture_default_str();
}

// For a move or a jog, after add_wait().
void add_progress(Parser& parser, CLI::App* subcommand) {
  subcommand
      ->add_flag("--progress", parser.raw.progress,
                 "with --wait: print the position every 100 ms also into a pipe or file (on a "
                 "terminal it always does)")
      ->needs(subcommand->get_option("--wait"));
}

void add_drive(CLI::App* subcommand, RawArguments& raw, bool required, bool shortest) {
  auto* speed = subcommand->add_option("--speed", raw.speed, "drive speed in percent, 0 to 100")
                    ->transform(kWholeNumber);
  auto* direction = subcommand->add_option("--direction", raw.direction,
                                           shortest ? "open, close or shortest" : "open or close");
  if (required) {
    speed->required();
    direction->required();
  } else {
    speed->capture_default_str();
    direction->capture_default_str();
  }
}

void define(Parser& parser) {
  CLI::App& app = parser.app;
  RawArguments& raw = parser.raw;
  GlobalOptions& global = parser.invocation.global;
  app.footer(kFooter);
  app.set_version_flag("--version", "valvectl " TEEJET_VERSION);
  app.require_subcommand(1);
  app.failure_message([](const CLI::App*, const CLI::Error& error) {
    return "valvectl: " + std::string(error.what()) +
           "\nRun valvectl --help for more information.\n";
  });
  // Global options may follow the subcommand too: `valvectl list --json`.
  app.fallthrough();
  app.add_option("--domain", global.domain, "DDS domain of the gateway")
      ->capture_default_str()
      ->transform(kWholeNumber)
      ->check(CLI::Range(0, dds::kMaxDomain));
  app.add_option("--profile", global.profile_file, "Fast DDS XML profiles file, as the gateway's")
      ->check(CLI::ExistingFile);
  app.add_flag("--json", global.json, "machine-readable output: JSON objects and arrays");
  app.add_option("--command-readers", global.command_readers,
                 "before sending, wait (up to --timeout) until N command readers matched: the "
                 "gateways and e.g. a teejet-record that must hear the command")
      ->type_name("N")
      ->transform(kWholeNumber);
  app.add_option("--timeout", raw.timeout_seconds,
                 "seconds to look for gateways and valves, and to wait for the first status")
      ->capture_default_str();

  parser.list = app.add_subcommand("list", "a table of every valve the gateways know");
  parser.list
      ->add_option("--wait-for", parser.invocation.list.wait_for_online,
                   "wait (up to --timeout) until at least N valves are online")
      ->type_name("N")
      ->transform(kWholeNumber);

  parser.watch = app.add_subcommand("watch", "the table, refreshed until Ctrl-C");
  parser.watch->add_option("--interval", raw.interval_ms, "refresh period in milliseconds")
      ->capture_default_str()
      ->transform(kWholeNumber)
      ->check(CLI::Range(50, 3'600'000));
  parser.duration = parser.watch->add_option("--duration", raw.duration_seconds,
                                             "stop after this many seconds (default: Ctrl-C)");
  parser.watch->add_option("--title", parser.invocation.watch.title,
                           "a line above the table on every refresh (e.g. a dashboard's URL)");

  parser.layout = app.add_subcommand(
      "layout", "where each valve sits: every place of the gateways' layouts, in machine order");

  parser.neighbours = app.add_subcommand(
      "neighbours",
      "the other ECUs that claimed addresses on each gateway's bus (ISOBUS), and each gateway's "
      "own claim of 0xD5");

  const auto add_location = [&](CLI::App* subcommand) {
    subcommand->add_option("LOCATION", raw.location, "a place of a gateway's layout (section-03)")
        ->required();
  };
  parser.assign = app.add_subcommand(
      "assign", "put a valve at its place in the layout (a valve fitted, or one replaced)");
  add_location(parser.assign);
  add_serial(parser.assign, raw);
  parser.assign->add_flag("--move", raw.move,
                          "the valve sits at another place of the layout: take it from there");
  parser.unassign =
      app.add_subcommand("unassign", "leave a place of the layout empty (its valve taken off)");
  add_location(parser.unassign);

  parser.identify = app.add_subcommand(
      "identify",
      "make a valve visibly move for the person at the boom: two short jogs out and "
      "back, ending where it started");
  add_valve(parser.identify, raw);

  parser.move = app.add_subcommand("move", "turn a valve to a position (Target Degrees)");
  add_serial_or_all(parser.move, raw);
  parser.move->add_option("--to", raw.degrees, "target position in degrees, 0 to 359.9")
      ->required();
  add_drive(parser.move, raw, /*required=*/false, /*shortest=*/true);
  add_wait(parser, parser.move, "follow the move until it completes, then show its position");
  add_progress(parser, parser.move);

  parser.stop = app.add_subcommand("stop", "stop a valve, or every online valve with --all");
  add_serial_or_all(parser.stop, raw);
  add_wait(parser, parser.stop, "wait until each stop is completed");

  parser.manual =
      app.add_subcommand("manual", "drive a valve until told otherwise (stays ACCEPTED)");
  add_valve(parser.manual, raw);
  add_drive(parser.manual, raw, /*required=*/true, /*shortest=*/false);

  parser.jog = app.add_subcommand("jog", "drive a valve for a time (Milliseconds to Run)");
  add_serial_or_all(parser.jog, raw);
  parser.jog->add_option("--ms", raw.milliseconds, "run time in milliseconds, 0 to 65535")
      ->required()
      ->transform(kWholeNumber);
  add_drive(parser.jog, raw, /*required=*/false, /*shortest=*/false);
  add_wait(parser, parser.jog, "wait until the run time is over");
  add_progress(parser, parser.jog);

  parser.clear_errors = app.add_subcommand("clear-errors", "clear a valve's latched errors");
  add_serial_or_all(parser.clear_errors, raw);
  add_wait(parser, parser.clear_errors, "wait until the clear is completed");

  parser.request = app.add_subcommand("request", "ask a valve to send a value");
  add_valve(parser.request, raw);
  parser.request->add_option("WHAT", raw.what, telemetry_words())->required();
  parser.request
      ->add_option("--every", raw.every_tenths,
                   "resend automatically every TENTHS of a second, 1 to 255; 0 = once")
      ->type_name("TENTHS")
      ->capture_default_str()
      ->transform(kWholeNumber);
  add_wait(parser, parser.request, "wait for the reply and print it");

  parser.baud = app.add_subcommand("baud", "request or set a valve's CAN bit rate");
  add_valve(parser.baud, raw);
  parser.baud->add_flag("--request", raw.baud_request, "ask the valve for its bit rate");
  parser.bit_rate = parser.baud->add_option(
      "--set", raw.bit_rate, "set the bit rate, 250000 or 500000 (the gateway must allow it)");
  parser.bit_rate->transform(kWholeNumber);
  add_wait(parser, parser.baud, "wait for the valve's reply (--request) and print it");
  command_line::refuse_empty_values(app);
}

std::uint32_t checked_serial(const std::string& text) {
  const auto serial = codec::parse_serial(text);
  if (!serial) usage_error("invalid SERIAL: " + serial.error().reason);
  return *serial;
}

// The options that carry each field of the protocol's messages.
constexpr std::array<std::pair<std::string_view, std::string_view>, 6> kOptionOfField{{
    {"speed_percent", "--speed"},
    {"direction", "--direction"},
    {"degrees", "--to"},
    {"milliseconds", "--ms"},
    {"resend_tenths", "--every"},
    {"bit_rate", "--set"},
}};

// The command for `message` with `fields` set, once the codec has checked every value against
// the sheet, as the gateway will. The codec names the field it refused; the person typed an
// option, so the message names that instead.
ValveCommand checked(const codec::ToValveMessage& message, const FieldValues& fields = {}) {
  auto command = with_fields(message, fields);
  auto checked_one = command ? checked_command(*command) : Result<ValveCommand>(command.error());
  if (checked_one) return *checked_one;
  const Error& error = checked_one.error();
  for (const auto& [field, option] : kOptionOfField) {
    if (error.field == field) usage_error(std::string(option) + " " + error.complaint);
  }
  usage_error(error.reason);
}

void build_command(Parser& parser, CLI::App* used) {
  RawArguments& raw = parser.raw;
  CommandRequest& request = parser.invocation.command;
  ValveCommand& command = request.command;
  request.subcommand = used->get_name();
  request.wait = raw.wait;
  request.progress = raw.progress;
  request.wait_timeout =
      seconds_option("--wait-timeout", raw.wait_timeout_seconds, kMaxWaitSeconds);

  // The subcommands given add_serial_or_all().
  if (used->get_option_no_throw("--all") != nullptr) {
    if (raw.all == !raw.serial.empty()) {
      usage_error(request.subcommand + ": give either a VALVE or --all");
    }
    if (!raw.gateway.empty() && !raw.all) {
      usage_error(request.subcommand + ": --gateway selects valves for --all");
    }
    request.every_online_valve = raw.all;
    request.only_gateway = raw.gateway;
  }
  if (!raw.serial.empty()) {
    const auto serial = codec::parse_serial(raw.serial);
    if (serial) {
      request.serials.push_back(*serial);
    } else if (layout::check_name(raw.serial)) {
      request.location = raw.serial;
    } else {
      const bool serial_like = (raw.serial.front() >= '0' && raw.serial.front() <= '9') ||
                               raw.serial.substr(0, 3) == "TJV" || raw.serial.substr(0, 3) == "tjv";
      usage_error("invalid VALVE '" + raw.serial + "': " +
                  (serial_like ? serial.error().reason
                               : "neither a serial (TJV123456 or 123456) nor a location name "
                                 "(lower-case letters, digits and '-', starting with a letter)"));
    }
  }

  const std::int64_t speed = raw.speed;
  if (used == parser.move) {
    command =
        checked(codec::TargetDegrees{},
                {{"speed_percent", speed}, {"direction", raw.direction}, {"degrees", raw.degrees}});
  } else if (used == parser.stop) {
    command = checked(codec::Stop{});
  } else if (used == parser.manual) {
    command = checked(codec::Manual{}, {{"speed_percent", speed}, {"direction", raw.direction}});
  } else if (used == parser.jog) {
    command =
        checked(codec::MillisecondsToRun{}, {{"speed_percent", speed},
                                             {"direction", raw.direction},
                                             {"milliseconds", std::int64_t{raw.milliseconds}}});
    // The run itself may take longer than the default backstop.
    if (parser.wait_timeout->count() == 0) {
      request.wait_timeout += std::chrono::milliseconds(raw.milliseconds);
    }
  } else if (used == parser.clear_errors) {
    command = checked(codec::ClearErrors{});
  } else if (used == parser.request) {
    const auto asked = codec::telemetry_request(raw.what);
    if (!asked) usage_error("request: '" + raw.what + "' is not one of " + telemetry_words());
    const bool resends = codec::find_field(codec::describe(*asked), "resend_tenths") != nullptr;
    if (!resends && raw.every_tenths != 0) {
      usage_error("request " + std::string(codec::subject(*asked)) +
                  ": a valve sends it once; --every is not allowed");
    }
    command = resends ? checked(*asked, {{"resend_tenths", std::int64_t{raw.every_tenths}}})
                      : checked(*asked);
  } else if (used == parser.baud) {
    const bool set = parser.bit_rate->count() > 0;
    if (set == raw.baud_request) usage_error("baud: give either --request or --set RATE");
    command = set ? checked(codec::BaudRate{codec::BaudAction::kSet, codec::kBitRate250k},
                            {{"bit_rate", std::int64_t{raw.bit_rate}}})
                  : checked(codec::BaudRate{codec::BaudAction::kRequest, codec::kBitRate250k});
  }
}

void build_invocation(Parser& parser) {
  Invocation& invocation = parser.invocation;
  invocation.global.timeout =
      seconds_option("--timeout", parser.raw.timeout_seconds, kMaxWaitSeconds);
  CLI::App* used = parser.app.get_subcommands().front();
  if (used == parser.list) {
    invocation.subcommand = Subcommand::kList;
  } else if (used == parser.layout) {
    invocation.subcommand = Subcommand::kLayout;
  } else if (used == parser.neighbours) {
    invocation.subcommand = Subcommand::kNeighbours;
  } else if (used == parser.assign || used == parser.unassign) {
    invocation.subcommand = Subcommand::kLayoutChange;
    LayoutChangeRequest& change = invocation.layout_change;
    if (const auto valid = layout::check_name(parser.raw.location); !valid) {
      usage_error("invalid LOCATION: " + valid.error().complaint);
    }
    change.location = parser.raw.location;
    change.kind = used == parser.assign ? LAYOUT_ASSIGN : LAYOUT_UNASSIGN;
    if (used == parser.assign) change.serial = checked_serial(parser.raw.serial);
    change.move = parser.raw.move;
  } else if (used == parser.watch) {
    invocation.subcommand = Subcommand::kWatch;
    invocation.watch.interval = std::chrono::milliseconds(parser.raw.interval_ms);
    if (parser.duration->count() > 0) {
      invocation.watch.duration =
          seconds_option("--duration", parser.raw.duration_seconds, kMaxWatchSeconds);
    }
  } else {
    invocation.subcommand = used == parser.identify ? Subcommand::kIdentify : Subcommand::kCommand;
    build_command(parser, used);
  }
}

}  // namespace

ParseOutcome parse_command_line(int argc, const char* const* argv) {
  Parser parser;
  define(parser);
  ParseOutcome outcome;
  std::ostringstream out;
  std::ostringstream err;
  try {
    parser.app.parse(argc, argv);
    for (CLI::App* subcommand : parser.app.get_subcommands()) {
      if (auto* option = subcommand->get_option_no_throw("--wait-timeout")) {
        parser.wait_timeout = option;
      }
    }
    build_invocation(parser);
  } catch (const CLI::ParseError& error) {
    // Help and --version exit 0; every other parse error is a usage error (EX_USAGE).
    const int cli_code = parser.app.exit(error, out, err);
    outcome.exit_code = cli_code == 0 ? kExitOk : kExitUsage;
    outcome.out = out.str();
    outcome.err = err.str();
    return outcome;
  }
  outcome.invocation = std::move(parser.invocation);
  return outcome;
}

}  // namespace teejet::valvectl
