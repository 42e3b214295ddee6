#pragma once

// What the dashboard's server (server.cpp) and the Foxglove port (foxglove_server.cpp) share of
// their transport. Included by those two translation units only: they hold Boost.Beast.

#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/http.hpp>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "page_command.hpp"
#include "sender.hpp"
#include "teejet/core/result.hpp"

namespace teejet::web::transport {

using Request = boost::beast::http::request<boost::beast::http::empty_body>;

inline std::optional<std::string_view> header(const Request& request,
                                              boost::beast::http::field field) {
  const auto found = request.find(field);
  if (found == request.end()) return std::nullopt;
  return std::string_view(found->value().data(), found->value().size());
}

// Where a server listens, from "ADDRESS:PORT" as parse_listen() made it.
inline Result<boost::asio::ip::tcp::endpoint> endpoint(const std::string& listen) {
  const auto colon = listen.rfind(':');
  std::string host = listen.substr(0, colon);
  if (host.size() > 2 && host.front() == '[') host = host.substr(1, host.size() - 2);
  boost::system::error_code error;
  const auto address = boost::asio::ip::make_address(host, error);
  if (colon == std::string::npos || error) {
    return Error{ErrorCode::kUnavailable, "cannot listen on " + listen};
  }
  return boost::asio::ip::tcp::endpoint(
      address, static_cast<unsigned short>(std::stoi(listen.substr(colon + 1))));
}

// Opens `acceptor` on `address` and listens (reusing the address, as a restarted server must);
// the first error.
inline boost::system::error_code listen_on(boost::asio::ip::tcp::acceptor& acceptor,
                                           const boost::asio::ip::tcp::endpoint& address) {
  boost::system::error_code error;
  acceptor.open(address.protocol(), error);
  if (!error) acceptor.set_option(boost::asio::ip::tcp::acceptor::reuse_address(true), error);
  if (!error) acceptor.bind(address, error);
  if (!error) acceptor.listen(boost::asio::socket_base::max_listen_connections, error);
  return error;
}

// A connection's place under its server's cap, from accept to the socket's close; it moves from
// the handshake's session into the WebSocket's. `open` counts a server's connections.
class ConnectionSlot {
 public:
  explicit ConnectionSlot(std::size_t& open) : open_(&open) { ++open; }
  ConnectionSlot(ConnectionSlot&& other) noexcept : open_(std::exchange(other.open_, nullptr)) {}
  ConnectionSlot& operator=(ConnectionSlot&&) = delete;
  ~ConnectionSlot() {
    if (open_ != nullptr) --*open_;
  }

 private:
  std::size_t* open_;
};

// The ids one client message was sent with, for DdsSender::answered once its answer is out.
class SentIds final : public CommandSender {
 public:
  explicit SentIds(DdsSender& sender) : sender_(&sender) {}

  Result<std::uint32_t> send(ValveCommand command) override {
    auto id = sender_->send(std::move(command));
    if (id) commands.push_back(*id);
    return id;
  }
  Result<std::uint32_t> send(LayoutChange change, const std::string& participant) override {
    auto id = sender_->send(std::move(change), participant);
    if (id) changes.push_back(*id);
    return id;
  }

  std::vector<std::uint32_t> commands;
  std::vector<std::uint32_t> changes;

 private:
  DdsSender* sender_;
};

}  // namespace teejet::web::transport
