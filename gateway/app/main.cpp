// teejet-gateway: every TeeJet valve on a CAN bus as keyed DDS instances, and DDS commands back
// to the right valve. See docs/gateway.md.

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <csignal>
#include <cstdlib>

#include "teejet/command_line.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/gateway/config.hpp"
#include "teejet/gateway/gateway.hpp"

namespace {

constexpr int kExitUsage = 2;
constexpr int kExitCannotStart = 1;
// Fast DDS stopped working inside this process (docs/gateway.md): the valves were stopped, and a
// supervisor restarts the gateway.
constexpr int kExitDdsStalled = 3;

// The signals that end the gateway, each through the same safe stop (docs/gateway.md). A stop
// asked for (SIGINT, SIGTERM) exits 0; the others exit 128 + n, as a shell reports a death by
// that signal, so that a supervisor can tell them apart and restart on them.
struct EndingSignal {
  int number;
  const char* name;
  int exit_status;
};
constexpr std::array kEndingSignals{
    EndingSignal{SIGTERM, "SIGTERM", 0},
    EndingSignal{SIGINT, "SIGINT", 0},
    EndingSignal{SIGHUP, "SIGHUP", 128 + SIGHUP},
    EndingSignal{SIGQUIT, "SIGQUIT", 128 + SIGQUIT},
    EndingSignal{SIGUSR1, "SIGUSR1", 128 + SIGUSR1},
    EndingSignal{SIGUSR2, "SIGUSR2", 128 + SIGUSR2},
    EndingSignal{SIGALRM, "SIGALRM", 128 + SIGALRM},
    EndingSignal{SIGXCPU, "SIGXCPU", 128 + SIGXCPU},
};

const EndingSignal& ending_signal(int number) {
  for (const auto& ending : kEndingSignals) {
    if (ending.number == number) return ending;
  }
  return kEndingSignals.front();  // sigwait() only returns signals of the set
}

// A log that cannot be written (its reader gone, a full disk, a file size limit) must fail the
// write, never kill the process before the valves are stopped: spdlog then drops the line.
void survive_failed_writes() {
  std::signal(SIGPIPE, SIG_IGN);
  std::signal(SIGXFSZ, SIG_IGN);
}

std::string default_gateway_name() {
  char host[256] = {};
  ::gethostname(host, sizeof host - 1);
  std::string name = std::string("teejet-gateway@") + host;
  name.resize(std::min(name.size(), teejet::dds::topics::kMaxGatewayNameLength));
  return name;
}

// The options as given; configure() applies only those the user named (app.count()).
struct Arguments {
  std::string can, profile, config_file, layout_file, name, log_level = "info";
  int domain = 0;
  bool allow_baud_change = false, keep_valves_running = false, record_frames = false;
};

void add_options(CLI::App& app, Arguments& arguments) {
  app.add_option("--can", arguments.can,
                 "SocketCAN interface (can0, vcan0), or sim:N for N simulated valves in-process")
      ->type_name("IFACE|sim:N");
  app.add_option("--domain", arguments.domain, "DDS domain id")
      ->check(CLI::Range(0, teejet::dds::kMaxDomain));
  app.add_option("--profile", arguments.profile, "Fast DDS XML profile file")
      ->check(CLI::ExistingFile);
  app.add_option("-c,--config", arguments.config_file, "YAML configuration (docs/gateway.md)")
      ->check(CLI::ExistingFile);
  app.add_option("--layout", arguments.layout_file,
                 "where each valve sits (docs/layout.md); the gateway rewrites this file")
      ->check(CLI::ExistingFile);
  app.add_option("--name", arguments.name,
                 "gateway name in presence and status (default: teejet-gateway@HOST)");
  app.add_flag("--allow-baud-change", arguments.allow_baud_change,
               "let DDS clients change a valve's CAN bit rate (refused otherwise)");
  app.add_flag("--keep-valves-running", arguments.keep_valves_running,
               "do not send Stop to every valve on exit");
  app.add_flag("--record-frames", arguments.record_frames,
               "publish every CAN frame sent and received on teejet/can/frame (best effort)");
  app.add_option("--log-level", arguments.log_level, "trace, debug, info, warn, error")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}));
}

// The defaults, then the config file, then the flags given on the command line, which win.
teejet::Result<teejet::gateway::GatewayConfig> configure(const CLI::App& app,
                                                         const Arguments& arguments) {
  teejet::gateway::GatewayConfig config;
  config.bridge.gateway_name = default_gateway_name();
  if (!arguments.config_file.empty()) {
    auto loaded = teejet::gateway::load_config_file(arguments.config_file, config);
    if (!loaded) return loaded.error();
    config = std::move(loaded).value();
  }
  if (app.count("--can")) config.can = arguments.can;
  if (app.count("--domain")) config.domain = arguments.domain;
  if (app.count("--profile")) config.profile_file = arguments.profile;
  if (app.count("--name")) config.bridge.gateway_name = arguments.name;
  if (app.count("--layout")) config.layout_file = arguments.layout_file;
  if (auto layout = teejet::gateway::read_layout_file(config); !layout) return layout.error();
  if (arguments.allow_baud_change) config.bridge.allow_baud_change = true;
  if (arguments.keep_valves_running) config.stop_valves_on_exit = false;
  if (arguments.record_frames) config.record_frames = true;
  if (config.can.empty()) {
    return teejet::Error{
        teejet::ErrorCode::kInvalidValue,
        "no CAN bus: give --can IFACE (or sim:N), or gateway.can in the config file"};
  }
  const auto& name = config.bridge.gateway_name;
  if (name.empty() || name.size() > teejet::dds::topics::kMaxGatewayNameLength) {
    return teejet::Error{
        teejet::ErrorCode::kInvalidValue,
        "the gateway name \"" + name + "\" is " + std::to_string(name.size()) +
            " characters long; it must be 1 to " +
            std::to_string(teejet::dds::topics::kMaxGatewayNameLength) +
            " (it keys teejet/gateway/status: a longer one would be cut and could become "
            "another gateway's)"};
  }
  return config;
}

// Signals are taken synchronously by run()'s sigwait(); every thread started later inherits the
// mask. One that arrives while the gateway starts waits until it runs, and one that arrives
// during the safe stop cannot cut it short.
sigset_t block_ending_signals() {
  sigset_t signals;
  sigemptyset(&signals);
  for (const auto& ending : kEndingSignals) sigaddset(&signals, ending.number);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  return signals;
}

// Runs the gateway until one of `signals` ends it; returns the exit status.
int run(const teejet::gateway::GatewayConfig& config, const sigset_t& signals) {
  auto backend = teejet::gateway::make_bus_backend(config);
  if (!backend) {
    spdlog::error("{}", backend.error().reason);
    return kExitUsage;
  }
  teejet::gateway::Gateway gateway(config, std::move(*backend));
  // A participant whose event thread is stuck cannot be deleted: the safe stop would wait
  // forever, so this one sends the Stops and ends the process without it.
  gateway.on_dds_stalled([&gateway](teejet::Duration) {
    spdlog::critical("stopped {} valve(s); exiting {} so that the service restarts",
                     gateway.stop_valves(), kExitDdsStalled);
    spdlog::shutdown();
    std::_Exit(kExitDdsStalled);
  });
  if (auto started = gateway.start(); !started) {
    spdlog::error("cannot start: {}", started.error().reason);
    return kExitCannotStart;
  }
  int number = SIGTERM;
  sigwait(&signals, &number);
  const EndingSignal& ending = ending_signal(number);
  spdlog::info("{}: shutting down", ending.name);
  gateway.stop();
  return ending.exit_status;
}

}  // namespace

int main(int argc, char** argv) {
  survive_failed_writes();
  CLI::App app{"Puts every TeeJet CAN valve on DDS, keyed by serial, and carries commands back.",
               "teejet-gateway"};
  app.set_version_flag("--version", "teejet-gateway " TEEJET_VERSION);
  Arguments arguments;
  add_options(app, arguments);
  teejet::command_line::refuse_empty_values(app);
  if (const auto exit_status = teejet::command_line::parse(app, argc, argv, kExitUsage)) {
    return *exit_status;
  }
  spdlog::set_level(spdlog::level::from_str(arguments.log_level));
  const auto config = configure(app, arguments);
  if (!config) {
    spdlog::error("{}", config.error().reason);
    return kExitUsage;
  }
  return run(*config, block_ending_signals());
}
