// Boost.Beast and Asio for the Foxglove port, in a translation unit of its own: the dashboard's
// server.cpp has its own stream type (TLS or plain) that this port does not need.

#include "foxglove_server.hpp"

#include <algorithm>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/write.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <iterator>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

#include "beast_transport.hpp"
#include "foxglove_feed.hpp"
#include "foxglove_protocol.hpp"
#include "foxglove_session.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/recording/latest_samples.hpp"
#include "token_guard.hpp"

namespace teejet::web {
namespace {

// As server.cpp has them: in a unity build both are one translation unit, where an alias may be
// declared twice to the same thing.
namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using namespace std::chrono_literals;
using transport::ConnectionSlot;
using transport::endpoint;
using transport::header;
using transport::Request;
using transport::SentIds;
using SteadyClock = std::chrono::steady_clock;

}  // namespace

namespace foxglove {
namespace {

// Foxglove apps, loggers and scripts at once; at the cap a new connection is closed at accept.
constexpr std::size_t kMaxConnections = 32;
constexpr std::uint32_t kMaxHeaderBytes = 8 * 1024;
// From accept to the whole handshake request.
constexpr auto kRequestDeadline = 10s;
constexpr auto kHandshakeTimeout = 10s;
// A client that answers nothing, not even the pings sent after half of it, is closed.
constexpr auto kIdleTimeout = 30s;
// A client that has messages dropped, and does not catch up (its outbox half empty) within this
// time, is closed: it reads slower than the data comes, or nothing. TEEJET_WEB_FOXGLOVE_STALL_S
// sets it for the tests.
constexpr auto kStallTimeout = 15s;
// Drops are told to their client at most this often, and logged at most every kLogPeriod.
constexpr auto kReportPeriod = 1s;
constexpr auto kLogPeriod = 10s;
// Loopback's send buffer grows to megabytes: a client that stopped reading would take that much
// before its outbox showed it.
constexpr int kSendBuffer = 64 * 1024;

using Response = http::response<http::string_body>;

// A positive whole number from the environment (the tests' settings), else `fallback`.
long from_environment(const char* name, long fallback) {
  const char* text = std::getenv(name);
  const long value = text == nullptr ? 0 : std::strtol(text, nullptr, 10);
  return value > 0 ? value : fallback;
}

std::uint64_t unix_ms() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::milliseconds>(
                                        std::chrono::system_clock::now().time_since_epoch())
                                        .count());
}

std::string describe(const tcp::endpoint& peer) {
  return "Foxglove client " + peer.address().to_string() + " port " + std::to_string(peer.port());
}

}  // namespace

class Connection;

}  // namespace foxglove

struct FoxgloveServer::Impl {
  Impl(const FoxgloveOptions& server_options, client::ValveView& valve_view, DdsSender& dds_sender)
      : options(server_options),
        view(valve_view),
        sender(dds_sender),
        tokens(server_options.policy.token, [] { return SteadyClock::now(); }),
        session_id(std::to_string(foxglove::unix_ms())) {}

  void accept();
  void distribute(std::vector<foxglove::FeedSample> batch);
  void send_state(foxglove::Connection& connection, const foxglove::Subscription& subscription);
  void report();
  // A gateway stopped or lost (the view's table, which follows its writers' liveliness and
  // matches; Fast DDS 2.9 gives a reader no sample for either): a new subscription must not
  // start from valves that look online.
  void forget_lost_gateways();

  const FoxgloveOptions options;
  client::ValveView& view;
  DdsSender& sender;
  TokenGuard tokens;  // unused without a token
  const std::string session_id;
  const std::chrono::seconds stall{
      foxglove::from_environment("TEEJET_WEB_FOXGLOVE_STALL_S", foxglove::kStallTimeout.count())};
  // TEEJET_WEB_FOXGLOVE_QUEUE_KB: a small bound lets a test fill it in seconds.
  const std::size_t queue_bytes =
      static_cast<std::size_t>(foxglove::from_environment(
          "TEEJET_WEB_FOXGLOVE_QUEUE_KB", static_cast<long>(foxglove::kMaxQueuedBytes / 1024))) *
      1024;
  // Touched on the I/O thread only. Declared before the io_context: the connections its
  // handlers still own when it goes count themselves out of these.
  std::size_t connections = 0;
  std::set<foxglove::Connection*> clients;  // those that got their 101
  bool said_full = false;
  recording::LatestSamples latest;
  std::set<std::string> forgotten;  // the lost participants whose samples left `latest`
  // Channels are advertised with their first message, as a recording adds them: a topic
  // nobody publishes costs a client nothing, and each channel carries the whole IDL (16 KB).
  std::vector<foxglove::Channel> advertised;
  std::vector<bool> is_advertised;  // by channel id
  asio::io_context io{1};
  tcp::acceptor acceptor{io};
  asio::steady_timer accept_retry{io};
  asio::steady_timer report_timer{io};
  asio::executor_work_guard<asio::io_context::executor_type> work{io.get_executor()};
  std::thread thread;
  // Published commands: the first waits up to 5 s for the gateways to match the command writer,
  // and no client's data waits with it.
  asio::io_context commands{1};
  asio::executor_work_guard<asio::io_context::executor_type> commands_work{commands.get_executor()};
  std::thread commands_thread;
  std::unique_ptr<foxglove::Feed> feed;
};

namespace foxglove {
namespace {

// Why a connection may not publish at all; nullopt when its publishes are checked one by one.
std::optional<std::string> publish_refusal(const CommandPolicy& policy, bool token_in_url) {
  if (!policy.allow_commands) return policy_refusal(policy, std::nullopt);
  if (policy.token.empty()) {
    return "teejet-web takes commands from Foxglove only with a token (--token-file): a "
           "Foxglove app runs in a browser, where any web page could reach this port";
  }
  if (!token_in_url) {
    return "commands need the token: connect with ws://HOST:PORT/?token=TOKEN";
  }
  return std::nullopt;
}

}  // namespace

// One Foxglove client after its handshake was read: the WebSocket, its Session and its writes.
class Connection final : public std::enable_shared_from_this<Connection> {
 public:
  Connection(FoxgloveServer::Impl& server, beast::tcp_stream&& stream, ConnectionSlot slot,
             std::string_view subprotocol, std::optional<std::string> token)
      : session(publish_refusal(server.options.policy, token.has_value()), server.queue_bytes),
        server_(server),
        socket_(std::move(stream)),
        slot_(std::move(slot)),
        subprotocol_(subprotocol),
        token_(std::move(token)) {
    beast::error_code ignored;
    tcp::socket& socket = socket_.next_layer().socket();
    peer_ = socket.remote_endpoint(ignored);
    socket.set_option(asio::socket_base::send_buffer_size(kSendBuffer), ignored);
  }
  ~Connection() {
    server_.clients.erase(this);
    server_.tokens.forget(token_key());
  }

  void accept(const Request& request) {
    socket_.set_option(websocket::stream_base::timeout{kHandshakeTimeout, kIdleTimeout, true});
    socket_.set_option(websocket::stream_base::decorator(
        [subprotocol = subprotocol_](websocket::response_type& response) {
          response.set(http::field::server, "teejet-web");
          response.set(http::field::sec_websocket_protocol, subprotocol);
        }));
    socket_.read_message_max(foxglove::kMaxClientMessageBytes);
    socket_.auto_fragment(false);
    socket_.async_accept(
        request, [self = shared_from_this()](beast::error_code error) { self->on_accept(error); });
  }

  // A message of one of this client's subscriptions, from the I/O thread.
  void deliver(std::uint32_t subscription, std::uint64_t timestamp_ns,
               std::span<const std::uint8_t> payload) {
    if (session.outbox.post_data(foxglove::message_data(subscription, timestamp_ns, payload))) {
      write_next();
    }
  }

  // A channel that just got its first message: advertised to every client.
  void advertise(const std::string& text) {
    session.outbox.post_text(text);
    write_next();
  }

  // Once a period: drops told and logged, a client that does not catch up closed.
  void report(SteadyClock::time_point now) {
    const std::uint64_t dropped = session.outbox.dropped();
    if (dropped > told_dropped_) {
      const std::uint64_t fresh = dropped - told_dropped_;
      session.outbox.post_status(foxglove::status(
          foxglove::Level::kWarning, "teejet-web dropped " + std::to_string(fresh) +
                                         " messages for this connection (" +
                                         std::to_string(dropped) +
                                         " in all): it reads slower than the valves publish; "
                                         "subscribe to fewer topics"));
      told_dropped_ = dropped;
      if (!behind_ || now - logged_at_ >= kLogPeriod) {
        std::cerr << "teejet-web: " << describe(peer_)
                  << (behind_ ? " still behind: " : " falls behind: ") << dropped
                  << " messages dropped so far\n";
        logged_at_ = now;
      }
      if (!behind_) behind_since_ = now;
      behind_ = true;
      write_next();
    } else if (session.outbox.queued_data_bytes() < session.outbox.max_queued_bytes() / 2) {
      behind_ = false;  // caught up
    }
    if (behind_ && now - behind_since_ > server_.stall) {
      std::cerr << "teejet-web: " << describe(peer_) << " has not caught up for "
                << server_.stall.count() << " s: closed\n";
      beast::error_code ignored;
      socket_.next_layer().socket().close(ignored);
    }
  }

  foxglove::Session session;

 private:
  void on_accept(beast::error_code error) {
    if (error) return;
    server_.clients.insert(this);
    std::cerr << "teejet-web: " << describe(peer_) << " connected (" << subprotocol_ << ")\n";
    session.outbox.post_text(foxglove::server_info(
        server_.options.name, !publish_refusal(server_.options.policy, true), server_.session_id));
    if (!server_.advertised.empty()) {
      session.outbox.post_text(foxglove::advertise(server_.advertised));
    }
    write_next();
    read();
  }

  void read() {
    socket_.async_read(input_, [self = shared_from_this()](beast::error_code error, std::size_t) {
      self->on_read(error);
    });
  }

  void on_read(beast::error_code error) {
    if (error) return stop();
    const auto data = input_.cdata();
    if (socket_.got_text()) {
      const std::string_view text(static_cast<const char*>(data.data()), data.size());
      auto reaction = session.on_text(text);
      for (auto& status : reaction.statuses) session.outbox.post_status(std::move(status));
      for (const auto& subscription : reaction.subscribed) {
        server_.send_state(*this, subscription);
      }
    } else {
      auto outcome =
          session.on_binary({static_cast<const std::uint8_t*>(data.data()), data.size()});
      if (auto* refusal = std::get_if<std::string>(&outcome)) {
        session.outbox.post_status(std::move(*refusal));
      } else {
        publish(std::move(std::get<foxglove::Publish>(outcome)));
      }
    }
    input_.consume(input_.size());
    write_next();
    read();
  }

  // Answered on the commands thread, the status queued back here; the sender keeps the
  // command's statuses for the page's ticks until that answer is out.
  void publish(foxglove::Publish request) {
    asio::post(server_.commands, [self = shared_from_this(),
                                  request = std::move(request)]() mutable {
      auto& server = self->server_;
      const auto check_token = [&](std::string_view token) -> std::optional<std::string> {
        const auto answer = server.tokens.check(self->token_key(), token);
        if (!answer.log.empty()) {
          std::cerr << "teejet-web: " << answer.log << " (from " << describe(self->peer_) << ")\n";
        }
        if (answer.verdict == TokenGuard::Verdict::kAccepted) return std::nullopt;
        return TokenGuard::reason(answer);
      };
      SentIds sent(server.sender);
      const auto answer =
          foxglove::answer_publish(request, server.sender.directory(), server.options.policy,
                                   self->token_, sent, check_token);
      // The connection's last reference goes on the I/O thread, which owns the server's set of
      // clients (its destructor leaves it), as the page's sessions do.
      asio::post(server.io, [self = std::move(self), answer, ids = std::move(sent.commands)] {
        self->session.outbox.post_status(foxglove::status(answer.level, answer.message));
        self->write_next();
        self->server_.sender.answered(ids, {});
      });
    });
  }

  void write_next() {
    if (stopped_) return;
    auto next = session.outbox.start_write();
    if (!next) return;
    auto self = shared_from_this();
    written_ = std::move(next->bytes);
    socket_.text(next->kind == foxglove::Outbox::Kind::kText);
    socket_.async_write(asio::buffer(written_), [self](beast::error_code error, std::size_t) {
      if (error) return self->stop();
      self->session.outbox.write_done();
      self->write_next();
    });
  }

  void stop() {
    if (std::exchange(stopped_, true)) return;
    server_.clients.erase(this);
    std::cerr << "teejet-web: " << describe(peer_) << " disconnected";
    if (session.outbox.dropped() > 0) {
      std::cerr << " (" << session.outbox.dropped() << " messages dropped for it in all)";
    }
    std::cerr << '\n';
  }

  std::uint64_t token_key() const { return reinterpret_cast<std::uintptr_t>(this); }

  FoxgloveServer::Impl& server_;
  websocket::stream<beast::tcp_stream> socket_;
  ConnectionSlot slot_;
  const std::string subprotocol_;
  const std::optional<std::string> token_;  // from the URL; read on the commands thread
  tcp::endpoint peer_;
  beast::flat_buffer input_;
  std::string written_;  // the frame being written
  bool stopped_ = false;
  std::uint64_t told_dropped_ = 0;
  bool behind_ = false;  // messages were dropped, and it has not caught up since
  SteadyClock::time_point behind_since_;
  SteadyClock::time_point logged_at_;
};

namespace {

// A connection until its handshake request is read: a Foxglove client goes on as a Connection;
// anything else is answered with why and closed.
class Handshake final : public std::enable_shared_from_this<Handshake> {
 public:
  Handshake(FoxgloveServer::Impl& server, tcp::socket&& socket, ConnectionSlot slot)
      : server_(server), stream_(std::move(socket)), slot_(std::move(slot)) {}

  void run() {
    parser_.header_limit(kMaxHeaderBytes);
    stream_.expires_after(kRequestDeadline);
    http::async_read(stream_, buffer_, parser_,
                     [self = shared_from_this()](beast::error_code error, std::size_t) {
                       self->on_request(error);
                     });
  }

 private:
  void on_request(beast::error_code error) {
    if (error == http::error::header_limit) {
      return refuse(http::status::request_header_fields_too_large, "headers too large");
    }
    if (error) return close();
    Request request = parser_.release();
    // A page of another site that rebinds its name to this address gives its own name here.
    const auto host = header(request, http::field::host);
    if (!host || !host_allowed(*host, server_.options.hosts)) {
      answer_ = forbidden_host_answer();
      return write_answer();
    }
    if (!websocket::is_upgrade(request)) {
      return refuse(http::status::bad_request,
                    "this port speaks the Foxglove WebSocket protocol: open it in Foxglove or "
                    "Lichtblick as ws://" +
                        std::string(*host) + "/ (teejet-web's page is on its --listen port)");
    }
    const auto subprotocol = foxglove::choose_subprotocol(
        header(request, http::field::sec_websocket_protocol).value_or(std::string_view()));
    if (!subprotocol) {
      return refuse(http::status::bad_request,
                    "no subprotocol teejet-web speaks was offered: foxglove.websocket.v1 or "
                    "foxglove.sdk.v1");
    }
    const std::string_view target(request.target().data(), request.target().size());
    auto token = foxglove::query_parameter(target, "token");
    stream_.expires_never();  // the WebSocket's own timeouts from here
    std::make_shared<Connection>(server_, std::move(stream_), std::move(slot_), *subprotocol,
                                 std::move(token))
        ->accept(request);
  }

  void refuse(http::status status, const std::string& reason) {
    Response response{status, 11};
    response.set(http::field::server, "teejet-web");
    response.set(http::field::content_type, "text/plain; charset=utf-8");
    response.body() = reason + "\n";
    response.keep_alive(false);
    response.prepare_payload();
    std::ostringstream text;
    text << response;
    answer_ = text.str();
    write_answer();
  }

  void write_answer() {
    asio::async_write(
        stream_, asio::buffer(answer_),
        [self = shared_from_this()](beast::error_code, std::size_t) { self->close(); });
  }

  void close() {
    beast::error_code ignored;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
    stream_.close();
  }

  FoxgloveServer::Impl& server_;
  beast::tcp_stream stream_;
  ConnectionSlot slot_;
  beast::flat_buffer buffer_;
  http::request_parser<http::empty_body> parser_;
  std::string answer_;
};

}  // namespace
}  // namespace foxglove

using foxglove::Connection;

void FoxgloveServer::Impl::accept() {
  acceptor.async_accept([this](beast::error_code error, tcp::socket socket) {
    if (error == asio::error::operation_aborted) return;
    if (error) {
      // Out of descriptors, most likely: wait for some to close instead of spinning.
      accept_retry.expires_after(100ms);
      accept_retry.async_wait([this](beast::error_code) { accept(); });
      return;
    }
    if (connections >= foxglove::kMaxConnections) {
      if (!std::exchange(said_full, true)) {
        std::cerr << "teejet-web: " << foxglove::kMaxConnections
                  << " Foxglove connections open: refusing more\n";
      }
      socket.close(error);
    } else {
      said_full = false;
      // Nagle's algorithm stays on: a message is 40 bytes, and a segment each would cost a
      // reader's buffer 20 times its size, so one that paused a few seconds lost segments and
      // waited out TCP's retransmission backoff (seconds) after it read on.
      std::make_shared<foxglove::Handshake>(*this, std::move(socket), ConnectionSlot(connections))
          ->run();
    }
    accept();
  });
}

void FoxgloveServer::Impl::distribute(std::vector<foxglove::FeedSample> batch) {
  const auto& types = recording::topic_types();
  for (auto& sample : batch) {
    // Every sample goes through the state, whoever is subscribed: a client's subscription
    // starts from it.
    if (!latest.admit(sample.topic, types[sample.topic], sample.taken)) continue;
    const std::uint32_t channel = foxglove::channel_id(sample.topic, sample.taken.disposed);
    if (channel == 0) continue;
    if (!is_advertised[channel]) {
      is_advertised[channel] = true;
      advertised.push_back(*foxglove::find_channel(channel));
      const std::string text = foxglove::advertise({advertised.back()});
      for (Connection* client : clients) client->advertise(text);
    }
    const std::uint64_t stamp =
        sample.taken.source_ns != 0 ? sample.taken.source_ns : sample.taken.received_ns;
    for (Connection* client : clients) {
      for (const std::uint32_t subscription : client->session.subscriptions(channel)) {
        client->deliver(subscription, stamp, sample.taken.payload);
      }
    }
  }
}

void FoxgloveServer::Impl::send_state(Connection& connection,
                                      const foxglove::Subscription& subscription) {
  const foxglove::Channel* channel = foxglove::find_channel(subscription.channel);
  if (channel == nullptr || channel->disposed) return;
  const auto& held = latest.held();
  for (auto it = held.lower_bound({channel->topic, recording::InstanceHandle{}});
       it != held.end() && it->first.first == channel->topic; ++it) {
    connection.deliver(subscription.id, it->second.source_ns, it->second.payload);
  }
}

void FoxgloveServer::Impl::forget_lost_gateways() {
  std::set<std::string> lost;
  for (const client::GatewaySummary& gateway : view.gateways()) {
    if (gateway.lost) lost.insert(gateway.participants.begin(), gateway.participants.end());
  }
  // Each participant once, when it is first lost: a dead gateway stays lost for good, and
  // naming every held sample's participant each second would be work for nothing.
  std::set<std::string> newly_lost;
  std::set_difference(lost.begin(), lost.end(), forgotten.begin(), forgotten.end(),
                      std::inserter(newly_lost, newly_lost.end()));
  if (!newly_lost.empty()) latest.forget_participants(newly_lost);
  forgotten = std::move(lost);
}

void FoxgloveServer::Impl::report() {
  report_timer.expires_after(foxglove::kReportPeriod);
  report_timer.async_wait([this](beast::error_code error) {
    if (error) return;
    const auto now = SteadyClock::now();
    forget_lost_gateways();
    // A connection may close itself while reporting: iterate over a copy.
    const std::vector<Connection*> open(clients.begin(), clients.end());
    for (Connection* client : open) client->report(now);
    report();
  });
}

Result<std::unique_ptr<FoxgloveServer>> FoxgloveServer::start(const FoxgloveOptions& options,
                                                              dds::Participant& participant,
                                                              client::ValveView& view,
                                                              DdsSender& sender) {
  const auto address = endpoint(options.listen);
  if (!address) return address.error();
  auto impl = std::make_unique<Impl>(options, view, sender);
  impl->is_advertised.resize(foxglove::channels().size() + 1);
  // Except the commands: a client publishes on them with their schema before any was sent.
  const foxglove::Channel* commands = foxglove::find_channel(dds::topics::kCommand);
  impl->advertised.push_back(*commands);
  impl->is_advertised[commands->id] = true;
  if (const auto error = transport::listen_on(impl->acceptor, *address)) {
    return Error{ErrorCode::kUnavailable,
                 "--foxglove: cannot listen on " + options.listen + ": " + error.message()};
  }
  Impl* raw = impl.get();
  auto feed = foxglove::Feed::start(participant, [raw](std::vector<foxglove::FeedSample> batch) {
    asio::post(raw->io,
               [raw, batch = std::move(batch)]() mutable { raw->distribute(std::move(batch)); });
  });
  if (!feed) return feed.error();
  impl->feed = std::move(*feed);
  impl->accept();
  impl->report();
  impl->thread = std::thread([&io = impl->io] { io.run(); });
  impl->commands_thread = std::thread([&commands = impl->commands] { commands.run(); });
  return std::unique_ptr<FoxgloveServer>(new FoxgloveServer(std::move(impl)));
}

FoxgloveServer::FoxgloveServer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

FoxgloveServer::~FoxgloveServer() {
  // The feed posts into the I/O thread's queue and a publish may still post its answer: both
  // stop before the I/O thread does.
  impl_->feed.reset();
  impl_->commands.stop();
  impl_->commands_thread.join();
  impl_->io.stop();
  impl_->thread.join();
}

}  // namespace teejet::web
