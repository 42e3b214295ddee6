// teejet-gateway: every TeeJet valve on a CAN bus as keyed DDS instances, and DDS commands back
// to the right valve. See docs/gateway.md.

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <csignal>

#include "config.hpp"
#include "gateway.hpp"

namespace {

std::string default_gateway_name() {
  char host[256] = {};
  ::gethostname(host, sizeof host - 1);
  return std::string("teejet-gateway@") + host;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Puts every TeeJet CAN valve on DDS, keyed by serial, and carries commands back.",
               "teejet-gateway"};
  app.set_version_flag("--version", "teejet-gateway " TEEJET_VERSION);
  std::string can, profile, config_file, name, log_level = "info";
  int domain = 0;
  bool allow_baud_change = false, keep_valves_running = false;
  app.add_option("--can", can,
                 "SocketCAN interface (can0, vcan0), or sim:N for N simulated valves in-process")
      ->type_name("IFACE|sim:N");
  app.add_option("--domain", domain, "DDS domain id")
      ->check(CLI::Range(0, teejet::dds::kMaxDomain));
  app.add_option("--profile", profile, "Fast DDS XML profile file")->check(CLI::ExistingFile);
  app.add_option("-c,--config", config_file, "YAML configuration (docs/gateway.md)")
      ->check(CLI::ExistingFile);
  app.add_option("--name", name,
                 "gateway name in presence and status (default: teejet-gateway@HOST)");
  app.add_flag("--allow-baud-change", allow_baud_change,
               "let DDS clients change a valve's CAN bit rate (refused otherwise)");
  app.add_flag("--keep-valves-running", keep_valves_running,
               "do not send Stop to every valve on exit");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}));
  CLI11_PARSE(app, argc, argv);
  spdlog::set_level(spdlog::level::from_str(log_level));

  teejet::gateway::GatewayConfig config;
  config.bridge.gateway_name = default_gateway_name();
  if (!config_file.empty()) {
    auto loaded = teejet::gateway::load_config_file(config_file, config);
    if (!loaded) {
      spdlog::error("{}", loaded.error().reason);
      return 2;
    }
    config = std::move(loaded).value();
  }
  // Flags given on the command line win over the file.
  if (app.count("--can")) config.can = can;
  if (app.count("--domain")) config.domain = domain;
  if (app.count("--profile")) config.profile_file = profile;
  if (app.count("--name")) config.bridge.gateway_name = name;
  if (allow_baud_change) config.bridge.allow_baud_change = true;
  if (keep_valves_running) config.stop_valves_on_exit = false;
  if (config.can.empty()) {
    spdlog::error("no CAN bus: give --can IFACE (or sim:N), or gateway.can in the config file");
    return 2;
  }

  // Signals are taken synchronously by this thread; every thread started later inherits the mask.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  auto backend = teejet::gateway::make_bus_backend(config);
  if (!backend) {
    spdlog::error("{}", backend.error().reason);
    return 2;
  }
  teejet::gateway::Gateway gateway(config, std::move(*backend));
  if (auto started = gateway.start(); !started) {
    spdlog::error("cannot start: {}", started.error().reason);
    return 1;
  }
  int signal = 0;
  sigwait(&signals, &signal);
  spdlog::info("{}: shutting down", signal == SIGINT ? "SIGINT" : "SIGTERM");
  gateway.stop();
  return 0;
}
