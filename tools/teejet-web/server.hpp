#pragma once

// teejet-web's HTTP and WebSocket server: the page's files, GET /api/valves, and the pages on
// /ws, each fed one batched update per tick. One I/O thread serves every connection
// asynchronously (Boost.Beast, kept inside server.cpp), so a slow or silent client holds a socket
// and a bounded buffer, never a thread. The JSON is the core's (dashboard_json, page_command), who
// may open a page is page_admission's, what every request must show and every answer carry
// request_guard's, the token's limits token_guard's, the files page_files'.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include "page_command.hpp"
#include "request_guard.hpp"
#include "sender.hpp"
#include "teejet/client/valve_view.hpp"
#include "teejet/core/result.hpp"

namespace teejet::web {

// A TLS server's certificate chain and key, loaded and checked (Asio's SSL, in server.cpp).
struct TlsIdentity;

// --tls-cert and --tls-key (PEM): an Error naming the option and the file when a file cannot be
// read, is not PEM, the key's file is open to group or others, or the key is not the
// certificate's.
Result<std::shared_ptr<TlsIdentity>> load_tls_identity(const std::filesystem::path& cert,
                                                       const std::filesystem::path& key);

struct ServerOptions {
  std::string listen;         // "ADDRESS:PORT", as parse_listen() made it
  std::filesystem::path www;  // the page's files, as find_www() found them
  CommandPolicy policy;
  AllowedHosts hosts;  // the Host names every request must give
  // With it every route is served over https and wss only; without, over plain http.
  std::shared_ptr<TlsIdentity> tls;
};

class Server {
 public:
  // Reads the page's files and serves on `options.listen` until destroyed; an Error when it cannot
  // read them or listen. `view` and `sender` must outlive the server.
  static Result<std::unique_ptr<Server>> start(const ServerOptions& options,
                                               client::ValveView& view, DdsSender& sender);
  // Stops the I/O thread and closes every connection.
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  // Hands every page what changed since its last update, and the statuses that arrived. From any
  // thread: the pages are fed on the I/O thread.
  void tick(std::uint64_t stamp_ms);

  struct Impl;  // the transport, in server.cpp

 private:
  explicit Server(std::unique_ptr<Impl> impl);

  std::unique_ptr<Impl> impl_;
};

}  // namespace teejet::web
