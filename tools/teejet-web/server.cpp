#include "server.hpp"

#include <civetweb.h>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <iostream>
#include <optional>
#include <string_view>
#include <utility>

#include "dashboard_json.hpp"
#include "page_outbox.hpp"

namespace teejet::web {
namespace {

// CivetWeb gives every open WebSocket a worker thread for its whole life. Pages beyond this many
// are refused, so that the threads left over always serve the page files and /api/valves.
constexpr std::size_t kMaxPages = 48;
constexpr std::size_t kHttpThreads = 8;

void write_frame(mg_connection* connection, PageOutbox::Frame frame, std::string_view data) {
  const int opcode = frame == PageOutbox::Frame::kText ? MG_WEBSOCKET_OPCODE_TEXT
                                                       : MG_WEBSOCKET_OPCODE_CONNECTION_CLOSE;
  mg_lock_connection(connection);
  mg_websocket_write(connection, opcode, data.data(), data.size());
  mg_unlock_connection(connection);
}

}  // namespace

// One open WebSocket: its outbox, and what it was last sent.
struct Server::Page {
  explicit Page(mg_connection* connection)
      : outbox([connection](PageOutbox::Frame frame, std::string_view data) {
          write_frame(connection, frame, data);
        }) {}

  PageOutbox outbox;
  UpdateBatcher batcher;  // under Server::mutex_
};

Result<std::unique_ptr<Server>> Server::start(const ServerOptions& options, client::ValveView& view,
                                              DdsSender& sender) {
  std::unique_ptr<Server> server(new Server(options, view, sender));
  mg_init_library(0);
  const std::string document_root = options.www.string();
  const std::string threads = std::to_string(kMaxPages + kHttpThreads);
  const char* server_options[] = {"listening_ports",
                                  options.listen.c_str(),
                                  "num_threads",
                                  threads.c_str(),
                                  "document_root",
                                  document_root.c_str(),
                                  "enable_directory_listing",
                                  "no",
                                  "additional_header",
                                  kSecurityHeaders,
                                  nullptr};
  mg_callbacks callbacks{};
  callbacks.begin_request = admit;
  server->context_ = mg_start(&callbacks, server.get(), server_options);
  if (server->context_ == nullptr) {
    return Error{ErrorCode::kUnavailable, "cannot listen on " + options.listen};
  }
  mg_set_request_handler(server->context_, "/api/valves$", valves, server.get());
  mg_set_websocket_handler(server->context_, "/ws$", connect, ready, message, close, server.get());
  return server;
}

Server::Server(const ServerOptions& options, client::ValveView& view, DdsSender& sender)
    : policy_(options.policy),
      hosts_(options.hosts),
      tokens_(options.policy.token, [] { return std::chrono::steady_clock::now(); }),
      view_(view),
      sender_(sender) {}

Server::~Server() {
  if (context_ != nullptr) mg_stop(context_);
  mg_exit_library();
}

void Server::tick(std::uint64_t stamp_ms) {
  const auto statuses = sender_.take_statuses();
  // With no page open (most of a bench's day) there is nobody to build a frame for; a page
  // that opens starts from a snapshot of its own.
  if (std::lock_guard lock(mutex_); pages_.empty()) return;
  const Targets targets = sender_.targets();
  const DashboardFrame frame = dashboard_frame(view_.snapshot(), targets);
  std::lock_guard lock(mutex_);
  for (auto& [connection, page] : pages_) {
    for (const CommandStatus& status : statuses) page->batcher.add_status(status);
    if (const auto update = page->batcher.tick(frame, stamp_ms)) post(*page, *update);
  }
}

// Before any route: a name teejet-web does not serve under is a rebound one (see request_guard).
int Server::admit(mg_connection* connection) {
  const auto& server = *static_cast<const Server*>(mg_get_user_data(mg_get_context(connection)));
  const char* host = mg_get_header(connection, "Host");
  if (host != nullptr && host_allowed(host, server.hosts_)) return 0;
  const std::string answer = forbidden_host_answer();
  mg_write(connection, answer.data(), answer.size());
  return 403;
}

int Server::valves(mg_connection* connection, void* data) {
  auto& server = *static_cast<Server*>(data);
  const mg_request_info* request = mg_get_request_info(connection);
  if (std::strcmp(request->request_method, "GET") != 0) {
    mg_send_http_error(connection, 405, "GET only");
    return 405;
  }
  const std::string body = valves_json(server.view_.snapshot(), server.sender_.targets()).dump();
  mg_send_http_ok(connection, "application/json", static_cast<long long>(body.size()));
  mg_write(connection, body.data(), body.size());
  return 200;
}

// A page of another site must not reach the bench through the operator's browser; a page over
// kMaxPages would take the last worker threads (the page retries with its backoff).
int Server::connect(const mg_connection* connection, void* data) {
  auto& server = *static_cast<Server*>(data);
  {
    std::lock_guard lock(server.mutex_);
    if (server.pages_.size() >= kMaxPages) return 1;
  }
  const char* origin = mg_get_header(connection, "Origin");
  if (origin == nullptr) return 0;  // not a browser
  return origin_allowed(origin, server.hosts_) ? 0 : 1;
}

void Server::ready(mg_connection* connection, void* data) {
  auto& server = *static_cast<Server*>(data);
  const DashboardFrame frame = dashboard_frame(server.view_.snapshot(), server.sender_.targets());
  std::lock_guard lock(server.mutex_);
  auto& page = server.pages_[connection];
  page = std::make_unique<Page>(connection);
  nlohmann::json snapshot = page->batcher.snapshot(frame);
  snapshot["commands"] = command_policy_json(server.policy_);
  snapshot["protocol"] = page_protocol_json();
  post(*page, snapshot);
}

int Server::message(mg_connection* connection, int flags, char* text, std::size_t length,
                    void* data) {
  auto& server = *static_cast<Server*>(data);
  const int opcode = flags & 0x0f;
  if (opcode == MG_WEBSOCKET_OPCODE_CONNECTION_CLOSE) return 0;
  if (opcode != MG_WEBSOCKET_OPCODE_TEXT) return 1;
  const auto check_token = [&](std::string_view token) -> std::optional<std::string> {
    const auto answer = server.tokens_.check(reinterpret_cast<std::uintptr_t>(connection), token);
    if (!answer.log.empty()) {
      const mg_request_info* peer = mg_get_request_info(connection);
      std::cerr << "teejet-web: " << answer.log << " (from " << peer->remote_addr << " port "
                << peer->remote_port << ")\n";
    }
    if (answer.verdict == TokenGuard::Verdict::kAccepted) return std::nullopt;
    return TokenGuard::reason(answer);
  };
  const nlohmann::json answer = handle_page_message({text, length}, server.view_.snapshot(),
                                                    server.policy_, server.sender_, check_token);
  std::lock_guard lock(server.mutex_);
  if (const auto page = server.pages_.find(connection); page != server.pages_.end()) {
    post(*page->second, answer);
  }
  return 1;
}

void Server::close(const mg_connection* connection, void* data) {
  auto& server = *static_cast<Server*>(data);
  std::unique_ptr<Page> page;
  {
    std::lock_guard lock(server.mutex_);
    const auto found = server.pages_.find(const_cast<mg_connection*>(connection));
    if (found == server.pages_.end()) return;
    page = std::move(found->second);
    server.pages_.erase(found);
  }
  server.tokens_.forget(reinterpret_cast<std::uintptr_t>(connection));
  // Joined here, out of the lock: the ticks of the other pages go on meanwhile.
  page.reset();
}

void Server::post(Page& page, const nlohmann::json& message) {
  if (page.outbox.post(message)) {
    std::cerr << "teejet-web: a page stopped reading (" << kMaxQueuedMessages
              << " messages waiting): dropped\n";
  }
}

}  // namespace teejet::web
