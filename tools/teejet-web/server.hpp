#pragma once

// teejet-web's HTTP and WebSocket server, on CivetWeb: the page's files, GET /api/valves, and
// the pages on /ws, each fed one batched update per tick through its own outbox. The JSON is the
// core's (dashboard_json, page_command); this only wires CivetWeb to it.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>

#include "page_command.hpp"
#include "request_guard.hpp"
#include "sender.hpp"
#include "teejet/client/valve_view.hpp"
#include "teejet/core/result.hpp"
#include "token_guard.hpp"

struct mg_connection;
struct mg_context;

namespace teejet::web {

struct ServerOptions {
  std::string listen;         // CivetWeb's listening_ports, as parse_listen() made it
  std::filesystem::path www;  // the page's files, as find_www() found them
  CommandPolicy policy;
  AllowedHosts hosts;  // the Host names every request must give
};

class Server {
 public:
  // Serves on `options.listen` until destroyed; an Error when it cannot listen. `view` and
  // `sender` must outlive the server.
  static Result<std::unique_ptr<Server>> start(const ServerOptions& options,
                                               client::ValveView& view, DdsSender& sender);
  // Stops CivetWeb: every page is closed and every callback has returned.
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  // Hands every page what changed since its last update, and the statuses that arrived.
  void tick(std::uint64_t stamp_ms);

 private:
  struct Page;

  Server(const ServerOptions& options, client::ValveView& view, DdsSender& sender);

  static int admit(mg_connection* connection);
  static int valves(mg_connection* connection, void* data);
  static int connect(const mg_connection* connection, void* data);
  static void ready(mg_connection* connection, void* data);
  static int message(mg_connection* connection, int flags, char* text, std::size_t length,
                     void* data);
  static void close(const mg_connection* connection, void* data);
  static void post(Page& page, const nlohmann::json& message);

  const CommandPolicy policy_;
  const AllowedHosts hosts_;
  TokenGuard tokens_;  // unused without a token
  client::ValveView& view_;
  DdsSender& sender_;
  std::mutex mutex_;
  std::map<mg_connection*, std::unique_ptr<Page>> pages_;  // the open WebSockets
  mg_context* context_ = nullptr;
};

}  // namespace teejet::web
