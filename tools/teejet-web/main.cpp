// teejet-web: the bench dashboard's server (issue 13). A DDS participant that keeps the client's
// table of valves and serves it over HTTP (GET /api/valves) and a WebSocket (/ws) that pushes one
// batched update per tick and, with --allow-commands, takes commands; with --foxglove, every
// topic to Foxglove or Lichtblick too. The JSON is the core's (dashboard_json, page_command), DDS
// commands the sender's, HTTP the server's, Foxglove's protocol foxglove_server's: this file is
// the command line and the order of the steps.

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#include "foxglove_server.hpp"
#include "listen_address.hpp"
#include "request_guard.hpp"
#include "sender.hpp"
#include "server.hpp"
#include "teejet/client/valve_view.hpp"
#include "teejet/command_line.hpp"
#include "teejet/dds/event_watchdog.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/stop_signals.hpp"
#include "token_file.hpp"
#include "web_assets.hpp"

namespace {

using namespace teejet;

constexpr int kExitFailure = 1;
constexpr int kExitUsage = 2;
constexpr int kExitDdsStalled = 3;
// 25 Hz: smooth enough for a plot, well under a browser's 60 fps.
constexpr auto kTickPeriod = std::chrono::milliseconds(40);

struct Options {
  std::string listen = web::kDefaultListen;  // after parse(): "ADDRESS:PORT", a literal address
  int domain = 0;
  std::string profile_file;
  bool allow_commands = false;
  std::string token;  // after parse(): from --token, --token-file or TEEJET_WEB_TOKEN
  std::string token_file;
  std::string www;
  std::vector<std::string> allowed_hosts;  // after parse(): lower case, checked
  std::string tls_cert;
  std::string tls_key;
  std::shared_ptr<web::TlsIdentity> tls;  // after parse(): loaded from both, or none
  std::string foxglove;                   // after parse(): "ADDRESS:PORT"; empty: no Foxglove
};

// One of --token-file, TEEJET_WEB_TOKEN and --token; nothing when none is given.
std::optional<int> take_token(Options& options) {
  const char* variable = std::getenv("TEEJET_WEB_TOKEN");
  const int sources = !options.token.empty() + !options.token_file.empty() + (variable != nullptr);
  if (sources == 0) return std::nullopt;
  if (sources > 1) {
    std::cerr << "teejet-web: give the token one way: --token-file, TEEJET_WEB_TOKEN or --token\n";
    return kExitUsage;
  }
  if (!options.allow_commands) {
    std::cerr << "teejet-web: a token (--token-file, TEEJET_WEB_TOKEN or --token) needs "
                 "--allow-commands\n";
    return kExitUsage;
  }
  if (!options.token_file.empty()) {
    const auto token = web::read_token_file(options.token_file);
    if (!token) {
      std::cerr << "teejet-web: " << token.error().reason << '\n';
      return kExitUsage;
    }
    options.token = *token;
  } else if (variable != nullptr) {
    options.token = variable;
    if (options.token.empty()) {
      std::cerr << "teejet-web: TEEJET_WEB_TOKEN is empty\n";
      return kExitUsage;
    }
  } else {
    std::cerr << "teejet-web: warning: --token is visible to every local user (ps, "
                 "/proc/PID/cmdline); use --token-file or TEEJET_WEB_TOKEN\n";
  }
  return std::nullopt;
}

// Nothing when teejet-web goes on; otherwise the status to exit with, the reason printed.
std::optional<int> parse(int argc, char** argv, Options& options) {
  CLI::App app{"The bench dashboard: every valve in a browser, live, over DDS.", "teejet-web"};
  app.footer(
      "The page, its files and the JSON messages: docs/web.md. Exit status: 0 after SIGINT or "
      "SIGTERM; 1 when DDS or the server could not start or the page was not found; 2 for a bad "
      "command line.");
  app.set_version_flag("--version", "teejet-web " TEEJET_VERSION);
  app.add_option("--listen", options.listen, "ADDR:PORT to serve on; 0.0.0.0 only when asked")
      ->capture_default_str();
  app.add_option("--domain", options.domain, "DDS domain of the gateways")
      ->capture_default_str()
      ->check(CLI::Range(0, teejet::dds::kMaxDomain));
  app.add_option("--profile", options.profile_file, "Fast DDS XML profiles file, as the gateway's")
      ->check(CLI::ExistingFile);
  app.add_option("--allowed-host", options.allowed_hosts,
                 "a host NAME people type to reach this server (repeatable); its addresses and, "
                 "on loopback, localhost are allowed already");
  app.add_flag("--allow-commands", options.allow_commands,
               "accept commands from the page (read-only otherwise)");
  app.add_option("--token-file", options.token_file,
                 "with --allow-commands: every command must carry the token in FILE (mode 600); "
                 "or set TEEJET_WEB_TOKEN");
  app.add_option("--token", options.token,
                 "the same on the command line, which local users can read: for a bench only");
  app.add_option("--tls-cert", options.tls_cert,
                 "serve https and wss only, with the certificate (chain) in FILE (PEM); needs "
                 "--tls-key");
  app.add_option("--tls-key", options.tls_key,
                 "the certificate's private key in FILE (PEM, unencrypted, mode 600)");
  app.add_option("--foxglove", options.foxglove,
                 "serve every topic to Foxglove or Lichtblick on [ADDR:]PORT (WebSocket; a port "
                 "alone is on 127.0.0.1, e.g. 8765); off without it");
  app.add_option("--www", options.www,
                 "directory of the page (default: www next to the executable, then "
                 "../share/teejet-web/www)");
  command_line::refuse_empty_values(app);
  if (const auto exit_status = command_line::parse(app, argc, argv, kExitUsage)) {
    return exit_status;
  }
  const auto listen = web::parse_listen(options.listen);
  if (!listen) {
    std::cerr << "teejet-web: " << listen.error().reason << '\n';
    return kExitUsage;
  }
  options.listen = *listen;
  if (!options.foxglove.empty()) {
    // A port alone: loopback, as an address must be typed to reach further.
    if (options.foxglove.find_first_not_of("0123456789") == std::string::npos) {
      options.foxglove = "127.0.0.1:" + options.foxglove;
    }
    const auto foxglove =
        web::parse_listen(options.foxglove, "--foxglove", web::kDefaultFoxgloveListen);
    if (!foxglove) {
      std::cerr << "teejet-web: " << foxglove.error().reason << '\n';
      return kExitUsage;
    }
    if (*foxglove == options.listen) {
      std::cerr << "teejet-web: --foxglove and --listen are both " << *foxglove
                << ": give each its own port\n";
      return kExitUsage;
    }
    options.foxglove = *foxglove;
  }
  for (std::string& name : options.allowed_hosts) {
    const auto allowed = web::parse_allowed_host(name);
    if (!allowed) {
      std::cerr << "teejet-web: " << allowed.error().reason << '\n';
      return kExitUsage;
    }
    name = *allowed;
  }
  if (options.tls_cert.empty() != options.tls_key.empty()) {
    std::cerr << "teejet-web: give --tls-cert and --tls-key together\n";
    return kExitUsage;
  }
  if (!options.tls_cert.empty()) {
    auto tls = web::load_tls_identity(options.tls_cert, options.tls_key);
    if (!tls) {
      std::cerr << "teejet-web: " << tls.error().reason << '\n';
      return kExitUsage;
    }
    options.tls = std::move(*tls);
  }
  return take_token(options);
}

Result<std::filesystem::path> find_page(const Options& options) {
  std::error_code exe_error;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", exe_error);
  return web::find_www(options.www, exe.parent_path());
}

// The telemetry the gateways resend every second or faster by default (`poll:` in
// config/gateway.example.yaml): the page takes it best effort, as a stream. Acknowledging each of
// 256 valves' samples cost teejet-web about a sixth of its CPU (docs/performance.md, "Scale").
const std::set<std::string> kStreamedTelemetry = {
    "position", "temperature", "voltage", "current", "degrees_per_second", "speed_direction"};

// Declared in this order so that the view goes before the participant it reads through.
struct Dds {
  std::unique_ptr<teejet::dds::Participant> participant;
  std::unique_ptr<teejet::dds::EventWatchdog> watchdog;  // null when it could not be made
  std::unique_ptr<client::ValveView> view;
};

// A participant whose event thread is stuck (docs/topics.md, "A participant that stops") shows
// every valve as it last was, and deleting it waits forever: the process ends instead, for its
// supervisor to start it again. A page sees the connection drop.
std::unique_ptr<teejet::dds::EventWatchdog> watch_event_thread(
    teejet::dds::Participant& participant) {
  auto watchdog = teejet::dds::EventWatchdog::create(
      participant, {.on_stalled = [](Duration silent_for) {
        std::cerr << "teejet-web: " << teejet::dds::EventWatchdog::describe(silent_for)
                  << "; exiting " << kExitDdsStalled << " so that the service restarts\n";
        std::_Exit(kExitDdsStalled);
      }});
  if (watchdog) return std::move(*watchdog);
  std::cerr << "teejet-web: warning: " << watchdog.error().reason << '\n';
  return nullptr;
}

Result<Dds> join_dds(const Options& options) {
  auto participant = teejet::dds::Participant::create(
      {.domain = options.domain, .profile_file = options.profile_file, .name = "teejet-web"});
  if (!participant) return participant.error();
  auto watchdog = watch_event_thread(**participant);
  auto view = client::ValveView::create(**participant, {.best_effort = kStreamedTelemetry});
  if (!view) return view.error();
  return Dds{std::move(*participant), std::move(watchdog), std::move(*view)};
}

void announce(const Options& options, const std::filesystem::path& www) {
  if (!options.token.empty() && !options.tls && !web::loopback_listen(options.listen)) {
    std::cerr << "teejet-web: warning: the token travels in clear over plain http on "
              << options.listen << ": anyone on that network can read it (--tls-cert, --tls-key)\n";
  }
  std::cerr << "teejet-web: " << (options.tls ? "https://" : "http://") << options.listen
            << "/ (domain " << options.domain << ", "
            << (options.allow_commands ? "commands allowed" : "read-only") << ", page from "
            << www.string() << ")\n";
  if (options.foxglove.empty()) return;
  if (!options.token.empty() && !web::loopback_listen(options.foxglove)) {
    std::cerr << "teejet-web: warning: Foxglove's token travels in clear over ws://"
              << options.foxglove << ": anyone on that network can read it\n";
  }
  std::cerr << "teejet-web: Foxglove: ws://" << options.foxglove << "/ ("
            << (options.allow_commands && !options.token.empty()
                    ? "commands with ?token= in the URL"
                    : "read-only")
            << ")\n";
}

std::uint64_t unix_ms() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::milliseconds>(
                                        std::chrono::system_clock::now().time_since_epoch())
                                        .count());
}

// Until SIGINT or SIGTERM. Stamped with the wall clock, which the page plots against.
void run_ticks(web::Server& server, const std::atomic<bool>& stop) {
  auto next = std::chrono::steady_clock::now();
  while (!stop) {
    server.tick(unix_ms());
    next += kTickPeriod;
    std::this_thread::sleep_until(next);
  }
}

int fail(const Error& error) {
  std::cerr << "teejet-web: " << error.reason << '\n';
  return kExitFailure;
}

}  // namespace

int main(int argc, char** argv) {
  static std::atomic<bool> stop{false};
  command_line::stop_on_sigint_or_sigterm(stop);
  Options options;
  if (const auto exit_status = parse(argc, argv, options)) return *exit_status;
  const auto www = find_page(options);
  if (!www) return fail(www.error());
  auto dds = join_dds(options);
  if (!dds) return fail(dds.error());
  web::DdsSender sender(*dds->participant, *dds->view);
  const auto server = web::Server::start(
      {.listen = options.listen,
       .www = *www,
       .policy = {options.allow_commands, options.token},
       .hosts = web::allowed_hosts(options.listen, web::local_addresses(), options.allowed_hosts),
       .tls = options.tls},
      *dds->view, sender);
  if (!server) return fail(server.error());
  std::unique_ptr<web::FoxgloveServer> foxglove;  // declared after the server: goes first
  if (!options.foxglove.empty()) {
    auto started = web::FoxgloveServer::start(
        {.listen = options.foxglove,
         .policy = {options.allow_commands, options.token},
         .hosts =
             web::allowed_hosts(options.foxglove, web::local_addresses(), options.allowed_hosts),
         .name =
             "teejet-web " TEEJET_VERSION " (DDS domain " + std::to_string(options.domain) + ")"},
        *dds->participant, *dds->view, sender);
    if (!started) return fail(started.error());
    foxglove = std::move(*started);
  }
  announce(options, *www);
  run_ticks(**server, stop);
  return 0;
}
