// valve-sim: a bank of simulated TeeJet CAN valves on a SocketCAN interface (or a virtual bus).

#include <pthread.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <deque>
#include <iostream>
#include <string>
#include <vector>

#include "config_file.hpp"
#include "setup.hpp"
#include "teejet/can/open_bus.hpp"
#include "teejet/codec/codec.hpp"
#include "teejet/codec/table.hpp"
#include "teejet/command_line.hpp"
#include "teejet/sim/simulator.hpp"

namespace {

namespace sim = teejet::sim;
namespace codec = teejet::codec;
namespace command_line = teejet::command_line;

constexpr int kExitUsage = 2;
constexpr int kExitBus = 1;

constexpr const char* kDescription =
    "Simulates a bank of TeeJet CAN valves, faithful to the TeeJet CAN Bus Valve Protocol "
    "sheet, on a SocketCAN interface.";

constexpr const char* kFooter = R"(Examples:
  valve-sim --can vcan0 --valves 4                   TJV000001..TJV000004 at 0xD8..0xDB
  valve-sim --can vcan0 --serials 123456,TJV123457 --opened 360 --dps 120 -v
  valve-sim --can vcan0 --valves 2 --inject-error TJV000002:high_voltage:16.2:15.5

Addresses: valves are ranked by serial, lowest first: the lowest takes 0xD8, the next 0xD9, ...
Signals: SIGINT/SIGTERM stop cleanly (exit 0). SIGUSR1 adds a valve at run time (the next
`hotplug:` entry of --config, else one serial below the lowest), which moves the valves above
it up one address, as the protocol sheet warns. SIGUSR2 makes the next --replace OLD:NEW: OLD
falls silent and NEW, with its settings, claims an address (a valve replaced on the machine).

Exit status: 0 after SIGINT/SIGTERM, 1 when the bus cannot be opened, 2 on usage errors.
See docs/valve-sim.md for the config file and every behaviour.)";

int usage_error(const std::string& message) {
  std::cerr << "valve-sim: " << message << "\nRun with --help for more information.\n";
  return kExitUsage;
}

teejet::Error usage(std::string reason) {
  return {teejet::ErrorCode::kInvalidValue, std::move(reason)};
}

std::shared_ptr<spdlog::logger> make_logger() {
  auto logger = spdlog::stderr_color_mt("valve-sim");
  logger->set_pattern("[%Y-%m-%d %H:%M:%S.%e] [%^%l%$] %v");
  logger->flush_on(spdlog::level::info);
  spdlog::set_default_logger(logger);
  return logger;
}

// Adds the next valve: a `hotplug:` entry while there are any, then an automatic serial.
void add_valve(sim::Simulator& simulator, const sim::Setup& setup,
               std::deque<sim::ValveConfig>& hotplug, spdlog::logger& logger) {
  sim::ValveConfig config = setup.base;
  std::vector<sim::InjectedError> errors = setup.base_errors;
  if (!hotplug.empty()) {
    config = hotplug.front();
    hotplug.pop_front();
    errors.clear();
    for (const auto& [serial, error] : setup.hotplug_errors) {
      if (serial == config.serial) errors.push_back(error);
    }
  } else {
    const auto serial = sim::serial_for_added_valve(simulator.assignments());
    if (!serial) {
      logger.error("SIGUSR1: no valve added: the bank is full or no serial is free");
      return;
    }
    config.serial = *serial;
  }
  if (const auto added = simulator.add_valve(config); !added) {
    logger.error("SIGUSR1: no valve added: {}", added.error().reason);
    return;
  }
  for (const auto& error : errors) {
    if (const auto injected = simulator.inject_error(config.serial, error); !injected) {
      logger.error("{}", injected.error().reason);
    }
  }
}

// The options as given; main() reads only those the user named (app.count()).
struct Arguments {
  std::string can_spec;
  unsigned valve_count = 0;
  std::vector<std::string> serial_texts;
  double dps = 0.0;
  double closed = 0.0;
  double opened = 0.0;
  double start = 0.0;
  std::string opening_direction;
  std::string config_path;
  std::vector<std::string> error_specs;
  std::vector<std::string> replace_specs;
  bool verbose = false;
};

// --replace OLD:NEW, as serials.
teejet::Result<std::pair<std::uint32_t, std::uint32_t>> parse_replacement(const std::string& spec) {
  const auto colon = spec.find(':');
  if (colon == std::string::npos) return usage("--replace " + spec + ": expected OLD:NEW");
  const auto old_serial = codec::parse_serial(spec.substr(0, colon));
  const auto new_serial = codec::parse_serial(spec.substr(colon + 1));
  if (!old_serial) return usage("--replace " + spec + ": " + old_serial.error().reason);
  if (!new_serial) return usage("--replace " + spec + ": " + new_serial.error().reason);
  return std::pair{*old_serial, *new_serial};
}

void add_options(CLI::App& app, Arguments& arguments) {
  app.add_option("--can", arguments.can_spec,
                 "SocketCAN interface (can0, vcan0); \"virtual:NAME\" is an in-process bus, "
                 "useful only when embedded")
      ->required()
      ->type_name("IFACE");
  auto* valves_option = app.add_option("--valves", arguments.valve_count,
                                       "simulate N valves, serials TJV000001..TJV00000N")
                            ->type_name("N");
  auto* serials_option =
      app.add_option("--serials", arguments.serial_texts,
                     "simulate these valves: comma-separated serials, TJV123456 or 123456")
          ->delimiter(',')
          ->type_name("LIST");
  valves_option->excludes(serials_option);
  app.add_option("--dps", arguments.dps,
                 "degrees per second at 100 % speed, 0 < DPS <= 359 "
                 "(default 90)")
      ->type_name("DPS");
  app.add_option("--closed", arguments.closed, "Closed Degrees (default 0)")->type_name("DEG");
  app.add_option("--opened", arguments.opened,
                 "Opened Degrees: at most 340 for a limited valve, 360 for a full-turn "
                 "valve (default 90)")
      ->type_name("DEG");
  app.add_option("--start", arguments.start, "position at power-up (default: Closed Degrees)")
      ->type_name("DEG");
  app.add_option("--opening-direction", arguments.opening_direction,
                 "which way the valves turn to open, looking from the top (default "
                 "clockwise)")
      ->check(CLI::IsMember({"clockwise", "counterclockwise"}))
      ->type_name("DIR");
  app.add_option("--config", arguments.config_path,
                 "YAML file: defaults, per-valve settings, errors to inject, valves to add on "
                 "SIGUSR1 (see docs/valve-sim.md)")
      ->type_name("FILE.yaml");
  std::string kinds;
  for (const std::string_view kind : codec::error_kinds()) {
    if (!kinds.empty()) kinds += ", ";
    kinds += kind;
  }
  app.add_option("--inject-error", arguments.error_specs,
                 "latch an error until Clear Errors, e.g. TJV000001:high_voltage:16.2:15.5; "
                 "kinds (the codec's) " +
                     kinds +
                     " (a kind with a direction takes :open or :close at the end); repeatable")
      ->type_name("SERIAL:KIND:VALUE:LIMIT");
  app.add_option("--replace", arguments.replace_specs,
                 "on each SIGUSR2 the next of these: valve OLD falls silent and NEW, with its "
                 "settings, takes its place (TJV000003:TJV000107); repeatable")
      ->type_name("OLD:NEW");
  app.add_flag("-v,--verbose", arguments.verbose, "log every frame received and sent, decoded");
}

// What the command line asks for; a serial or error that does not parse is an Error saying so.
teejet::Result<sim::CommandLine> command_line_of(const CLI::App& app, const Arguments& arguments) {
  sim::CommandLine command_line;
  if (app.count("--valves") > 0) command_line.valve_count = arguments.valve_count;
  for (const auto& text : arguments.serial_texts) {
    const auto serial = codec::parse_serial(text);
    if (!serial) return usage("--serials: " + serial.error().reason);
    command_line.serials.push_back(*serial);
  }
  if (app.count("--serials") > 0 && command_line.serials.empty()) {
    return usage("--serials: give at least one serial");
  }
  auto& settings = command_line.settings;
  if (app.count("--dps") > 0) settings.degrees_per_second = arguments.dps;
  if (app.count("--closed") > 0) settings.closed_degrees = arguments.closed;
  if (app.count("--opened") > 0) settings.opened_degrees = arguments.opened;
  if (app.count("--start") > 0) settings.start_degrees = arguments.start;
  if (app.count("--opening-direction") > 0) {
    settings.opening_direction = sim::parse_rotation(arguments.opening_direction);
  }
  for (const auto& spec : arguments.error_specs) {
    const auto parsed = sim::parse_error_spec(spec);
    if (!parsed) return usage("--inject-error " + parsed.error().reason);
    command_line.errors.push_back(*parsed);
  }
  return command_line;
}

// The bank to simulate: the command line composed with the --config file.
teejet::Result<sim::Setup> setup_of(const CLI::App& app, const Arguments& arguments) {
  auto command_line = command_line_of(app, arguments);
  if (!command_line) return command_line.error();
  sim::ConfigFile file;
  if (!arguments.config_path.empty()) {
    auto loaded = sim::load_config(arguments.config_path);
    if (!loaded) return loaded.error();
    file = std::move(loaded).value();
  }
  return sim::compose_setup(*command_line, file);
}

// SIGINT, SIGTERM and SIGUSR1 are taken synchronously by serve_signals(); threads started later
// (the simulator's) inherit the mask.
sigset_t block_signals() {
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGUSR1);
  sigaddset(&signals, SIGUSR2);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  return signals;
}

// Adds a valve on every SIGUSR1, replaces one on every SIGUSR2; returns on SIGINT or SIGTERM.
void serve_signals(const sigset_t& signals, sim::Simulator& simulator, const sim::Setup& setup,
                   std::deque<std::pair<std::uint32_t, std::uint32_t>> replacements,
                   spdlog::logger& logger) {
  std::deque<sim::ValveConfig> hotplug(setup.hotplug.begin(), setup.hotplug.end());
  for (;;) {
    int received = 0;
    if (sigwait(&signals, &received) != 0) continue;
    if (received == SIGUSR1) {
      add_valve(simulator, setup, hotplug, logger);
      continue;
    }
    if (received == SIGUSR2) {
      if (replacements.empty()) {
        logger.error("SIGUSR2: no valve replaced: no --replace left");
        continue;
      }
      const auto [old_serial, new_serial] = replacements.front();
      replacements.pop_front();
      if (const auto replaced = simulator.replace_valve(old_serial, new_serial); !replaced) {
        logger.error("SIGUSR2: {}", replaced.error().reason);
      }
      continue;
    }
    logger.info("{}: stopping", received == SIGINT ? "SIGINT" : "SIGTERM");
    return;
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{kDescription, "valve-sim"};
  app.footer(kFooter);
  app.set_version_flag("--version", "valve-sim " TEEJET_VERSION);
  Arguments arguments;
  add_options(app, arguments);
  command_line::refuse_empty_values(app);
  if (const auto exit_status = command_line::parse(app, argc, argv, kExitUsage)) {
    return *exit_status;
  }
  const auto setup = setup_of(app, arguments);
  if (!setup) return usage_error(setup.error().reason);
  std::deque<std::pair<std::uint32_t, std::uint32_t>> replacements;
  for (const auto& spec : arguments.replace_specs) {
    const auto replacement = parse_replacement(spec);
    if (!replacement) return usage_error(replacement.error().reason);
    replacements.push_back(*replacement);
  }

  const sigset_t signals = block_signals();
  const auto logger = make_logger();
  sim::Simulator simulator(
      teejet::can::make_bus(arguments.can_spec, teejet::can::valve_side_filters()),
      {.valves = setup->valves,
       .errors = setup->errors,
       .verbose = arguments.verbose,
       .logger = logger});
  if (const auto started = simulator.start(); !started) {
    std::cerr << "valve-sim: " << started.error().reason << '\n';
    return kExitBus;
  }
  logger->info(
      "simulating {} valve(s) on {}; SIGUSR1 adds one, SIGUSR2 replaces one, "
      "SIGINT/SIGTERM stop",
      setup->valves.size(), arguments.can_spec);
  serve_signals(signals, simulator, *setup, std::move(replacements), *logger);
  simulator.stop();
  logger->info("sent {} frames, handled {}", simulator.frames_sent(), simulator.frames_handled());
  return 0;
}
