// teejet-web: the bench dashboard's server (issue 13). A DDS participant that keeps the client's
// table of valves and serves it over HTTP (GET /api/valves) and a WebSocket (/ws) that pushes one
// batched update per tick and, with --allow-commands, takes commands. The JSON is the core's
// (dashboard_json, page_command); this file only wires CivetWeb and DDS to it.

#include <civetweb.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <filesystem>
#include <iostream>
#include <iterator>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <stop_token>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "dashboard_json.hpp"
#include "listen_address.hpp"
#include "page_command.hpp"
#include "page_outbox.hpp"
#include "teejet/client/command_client.hpp"
#include "teejet/client/valve_view.hpp"
#include "teejet/command_line.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/stop_signals.hpp"
#include "web_assets.hpp"

namespace {

using namespace teejet;
using Clock = std::chrono::steady_clock;

constexpr int kExitFailure = 1;
constexpr int kExitUsage = 2;
// 25 Hz: smooth enough for a plot, well under a browser's 60 fps.
constexpr auto kTickPeriod = std::chrono::milliseconds(40);
// CivetWeb gives every open WebSocket a worker thread for its whole life. Pages beyond this many
// are refused, so that the threads left over always serve the page files and /api/valves.
constexpr std::size_t kMaxPages = 48;
constexpr std::size_t kHttpThreads = 8;
// How long the first command waits for the gateways to match the command writer.
constexpr auto kConnectTimeout = std::chrono::seconds(5);

struct Options {
  std::string listen = web::kDefaultListen;
  int domain = 0;
  std::string profile_file;
  bool allow_commands = false;
  std::string token;
  std::string www;
};

// Writes commands through the client's CommandClient and follows their statuses for the ticks.
class DdsSender final : public web::CommandSender {
 public:
  DdsSender(teejet::dds::Participant& participant, client::ValveView& view)
      : participant_(participant), view_(view) {}

  Result<std::uint32_t> send(ValveCommand command) override {
    auto client = connected();
    if (!client) return client.error();
    std::lock_guard lock(mutex_);
    const auto id = (*client)->send(command);
    if (!id) return Error{ErrorCode::kInvalidValue, "DDS did not take the command"};
    command.command_id(*id);
    tracker_.on_sent(command);
    open_.insert(*id);
    return *id;
  }

  // The statuses that arrived since the last call, in order; the tick hands them to every page.
  std::vector<CommandStatus> take_statuses() {
    std::lock_guard lock(mutex_);
    std::vector<CommandStatus> statuses;
    if (!client_) return statuses;
    for (auto it = open_.begin(); it != open_.end();) {
      bool final = false;
      while (const auto status = client_->next_status(*it, Clock::now())) {
        tracker_.on_status(*status);
        statuses.push_back(*status);
        final = final || status->state() != COMMAND_ACCEPTED;
      }
      it = final ? open_.erase(it) : std::next(it);
    }
    return statuses;
  }

  web::Targets targets() {
    std::lock_guard lock(mutex_);
    return tracker_.targets();
  }

 private:
  // Connects on the first command: a read-only dashboard never announces a command writer.
  // Under its own lock, so that ticks go on while discovery takes its time.
  Result<client::CommandClient*> connected() {
    std::lock_guard connecting(connect_mutex_);
    {
      std::lock_guard lock(mutex_);
      if (client_) return client_.get();
    }
    auto made = client::CommandClient::create(participant_, client::default_origin("teejet-web"));
    if (!made) return made.error();
    const std::size_t gateways = std::max<std::size_t>(1, view_.snapshot().gateways().size());
    const std::atomic<bool> never{false};
    const auto matched = (*made)->connect(gateways, 0, Clock::now() + kConnectTimeout, never);
    if (!matched) return matched.error();
    if (!*matched) {
      return Error{ErrorCode::kInvalidValue, "no gateway subscribes to commands (waited 5 s)"};
    }
    std::lock_guard lock(mutex_);
    client_ = std::move(*made);
    return client_.get();
  }

  teejet::dds::Participant& participant_;
  client::ValveView& view_;
  std::mutex connect_mutex_;
  std::mutex mutex_;
  std::unique_ptr<client::CommandClient> client_;
  web::TargetTracker tracker_;
  std::set<std::uint32_t> open_;  // command ids not yet final
};

// One open WebSocket: its outbox, and what it was last sent.
struct Page {
  explicit Page(mg_connection* connection)
      : outbox([connection](web::PageOutbox::Frame frame, std::string_view data) {
          mg_lock_connection(connection);
          mg_websocket_write(connection,
                             frame == web::PageOutbox::Frame::kText
                                 ? MG_WEBSOCKET_OPCODE_TEXT
                                 : MG_WEBSOCKET_OPCODE_CONNECTION_CLOSE,
                             data.data(), data.size());
          mg_unlock_connection(connection);
        }) {}

  web::PageOutbox outbox;
  web::UpdateBatcher batcher;  // under Server::mutex_
};

// The open WebSockets, each with what it was last sent.
class Server {
 public:
  Server(const Options& options, client::ValveView& view, DdsSender& sender)
      : policy_{options.allow_commands, options.token}, view_(view), sender_(sender) {}

  void tick(std::uint64_t stamp_ms) {
    const auto statuses = sender_.take_statuses();
    // With no page open (most of a bench's day) there is nobody to build a frame for; a page
    // that opens starts from a snapshot of its own.
    if (std::lock_guard lock(mutex_); pages_.empty()) return;
    const web::Targets targets = sender_.targets();
    const web::DashboardFrame frame = web::dashboard_frame(view_.snapshot(), targets);
    std::lock_guard lock(mutex_);
    for (auto& [connection, page] : pages_) {
      for (const CommandStatus& status : statuses) page->batcher.add_status(status);
      if (const auto update = page->batcher.tick(frame, stamp_ms)) post(*page, *update);
    }
  }

  static int valves(mg_connection* connection, void* data) {
    auto& server = *static_cast<Server*>(data);
    const mg_request_info* request = mg_get_request_info(connection);
    if (std::strcmp(request->request_method, "GET") != 0) {
      mg_send_http_error(connection, 405, "GET only");
      return 405;
    }
    const std::string body =
        web::valves_json(server.view_.snapshot(), server.sender_.targets()).dump();
    mg_send_http_ok(connection, "application/json", static_cast<long long>(body.size()));
    mg_write(connection, body.data(), body.size());
    return 200;
  }

  // A page of another site must not reach the bench through the operator's browser; a page over
  // kMaxPages would take the last worker threads (the page retries with its backoff).
  static int connect(const mg_connection* connection, void* data) {
    auto& server = *static_cast<Server*>(data);
    {
      std::lock_guard lock(server.mutex_);
      if (server.pages_.size() >= kMaxPages) return 1;
    }
    const char* origin = mg_get_header(connection, "Origin");
    const char* host = mg_get_header(connection, "Host");
    if (origin == nullptr) return 0;  // not a browser
    return host != nullptr && std::string(origin) == std::string("http://") + host ? 0 : 1;
  }

  static void ready(mg_connection* connection, void* data) {
    auto& server = *static_cast<Server*>(data);
    const web::DashboardFrame frame =
        web::dashboard_frame(server.view_.snapshot(), server.sender_.targets());
    std::lock_guard lock(server.mutex_);
    auto& page = server.pages_[connection];
    page = std::make_unique<Page>(connection);
    nlohmann::json snapshot = page->batcher.snapshot(frame);
    snapshot["commands"] = web::command_policy_json(server.policy_);
    post(*page, snapshot);
  }

  static int message(mg_connection* connection, int flags, char* text, std::size_t length,
                     void* data) {
    auto& server = *static_cast<Server*>(data);
    const int opcode = flags & 0x0f;
    if (opcode == MG_WEBSOCKET_OPCODE_CONNECTION_CLOSE) return 0;
    if (opcode != MG_WEBSOCKET_OPCODE_TEXT) return 1;
    const nlohmann::json answer = web::handle_page_message({text, length}, server.view_.snapshot(),
                                                           server.policy_, server.sender_);
    std::lock_guard lock(server.mutex_);
    if (const auto page = server.pages_.find(connection); page != server.pages_.end()) {
      post(*page->second, answer);
    }
    return 1;
  }

  static void close(const mg_connection* connection, void* data) {
    auto& server = *static_cast<Server*>(data);
    std::unique_ptr<Page> page;
    {
      std::lock_guard lock(server.mutex_);
      const auto found = server.pages_.find(const_cast<mg_connection*>(connection));
      if (found == server.pages_.end()) return;
      page = std::move(found->second);
      server.pages_.erase(found);
    }
    // Joined here, out of the lock: the ticks of the other pages go on meanwhile.
    page.reset();
  }

 private:
  static void post(Page& page, const nlohmann::json& message) {
    if (page.outbox.post(message)) {
      std::cerr << "teejet-web: a page stopped reading (" << web::kMaxQueuedMessages
                << " messages waiting): dropped\n";
    }
  }

  const web::CommandPolicy policy_;
  client::ValveView& view_;
  DdsSender& sender_;
  std::mutex mutex_;
  std::map<mg_connection*, std::unique_ptr<Page>> pages_;
};

std::uint64_t unix_ms() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::milliseconds>(
                                        std::chrono::system_clock::now().time_since_epoch())
                                        .count());
}

}  // namespace

int main(int argc, char** argv) {
  static std::atomic<bool> stop{false};
  command_line::stop_on_sigint_or_sigterm(stop);

  Options options;
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
  app.add_flag("--allow-commands", options.allow_commands,
               "accept commands from the page (read-only otherwise)");
  app.add_option("--token", options.token, "with --allow-commands: every command must carry it");
  app.add_option("--www", options.www,
                 "directory of the page (default: www next to the executable, then "
                 "../share/teejet-web/www)");
  command_line::refuse_empty_values(app);
  if (const auto exit_status = command_line::parse(app, argc, argv, kExitUsage)) {
    return *exit_status;
  }
  const auto listen = web::parse_listen(options.listen);
  if (!listen) {
    std::cerr << "teejet-web: " << listen.error().reason << '\n';
    return kExitUsage;
  }
  if (!options.token.empty() && !options.allow_commands) {
    std::cerr << "teejet-web: --token needs --allow-commands\n";
    return kExitUsage;
  }

  std::error_code exe_error;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", exe_error);
  const auto www = web::find_www(options.www, exe.parent_path());
  if (!www) {
    std::cerr << "teejet-web: " << www.error().reason << '\n';
    return kExitFailure;
  }

  auto participant = teejet::dds::Participant::create(
      {.domain = options.domain, .profile_file = options.profile_file, .name = "teejet-web"});
  if (!participant) {
    std::cerr << "teejet-web: " << participant.error().reason << '\n';
    return kExitFailure;
  }
  auto view = client::ValveView::create(**participant);
  if (!view) {
    std::cerr << "teejet-web: " << view.error().reason << '\n';
    return kExitFailure;
  }
  DdsSender sender(**participant, **view);
  Server server(options, **view, sender);

  mg_init_library(0);
  const std::string document_root = www->string();
  const std::string threads = std::to_string(kMaxPages + kHttpThreads);
  const char* server_options[] = {"listening_ports",
                                  listen->c_str(),
                                  "num_threads",
                                  threads.c_str(),
                                  "document_root",
                                  document_root.c_str(),
                                  "enable_directory_listing",
                                  "no",
                                  nullptr};
  mg_callbacks callbacks{};
  mg_context* context = mg_start(&callbacks, nullptr, server_options);
  if (context == nullptr) {
    std::cerr << "teejet-web: cannot listen on " << *listen << '\n';
    mg_exit_library();
    return kExitFailure;
  }
  mg_set_request_handler(context, "/api/valves$", Server::valves, &server);
  mg_set_websocket_handler(context, "/ws$", Server::connect, Server::ready, Server::message,
                           Server::close, &server);
  std::cerr << "teejet-web: http://" << *listen << "/ (domain " << options.domain << ", "
            << (options.allow_commands ? "commands allowed" : "read-only") << ", page from "
            << document_root << ")\n";

  auto next = Clock::now();
  while (!stop) {
    server.tick(unix_ms());
    next += kTickPeriod;
    std::this_thread::sleep_until(next);
  }
  mg_stop(context);
  mg_exit_library();
  return 0;
}
