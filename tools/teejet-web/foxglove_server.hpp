#pragma once

// teejet-web's Foxglove WebSocket server (--foxglove ADDR:PORT): the teejet topics live in
// Foxglove or Lichtblick, with the channels and schemas of a recording. One I/O thread serves
// every client asynchronously (Boost.Beast, inside foxglove_server.cpp); the protocol is
// foxglove_protocol's, each client's state and outbox foxglove_session's, the samples
// foxglove_feed's, the checks of a published command page_command's. docs/web.md describes it.

#include <memory>
#include <string>

#include "page_command.hpp"
#include "request_guard.hpp"
#include "sender.hpp"
#include "teejet/client/valve_view.hpp"
#include "teejet/core/result.hpp"
#include "teejet/dds/participant.hpp"

namespace teejet::web {

inline constexpr const char* kDefaultFoxgloveListen = "127.0.0.1:8765";

struct FoxgloveOptions {
  std::string listen;  // "ADDRESS:PORT", as parse_listen() made it
  // Commands are taken from Foxglove clients with --allow-commands and a token only: a Foxglove
  // app runs in the operator's browser under its own origin, so the origin check that guards the
  // page cannot guard this port.
  CommandPolicy policy;
  AllowedHosts hosts;  // the Host names a connection must give
  std::string name;    // serverInfo's name
};

class FoxgloveServer {
 public:
  // Subscribes to every teejet topic on `participant` and serves on `options.listen` until
  // destroyed; an Error when DDS refuses a reader or the port cannot be listened on. The
  // participant, `view` and `sender` must outlive the server.
  static Result<std::unique_ptr<FoxgloveServer>> start(const FoxgloveOptions& options,
                                                       dds::Participant& participant,
                                                       client::ValveView& view, DdsSender& sender);
  ~FoxgloveServer();
  FoxgloveServer(const FoxgloveServer&) = delete;
  FoxgloveServer& operator=(const FoxgloveServer&) = delete;

  struct Impl;  // the transport, in foxglove_server.cpp

 private:
  explicit FoxgloveServer(std::unique_ptr<Impl> impl);

  std::unique_ptr<Impl> impl_;
};

}  // namespace teejet::web
