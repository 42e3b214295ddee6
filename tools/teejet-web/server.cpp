// The only translation unit with Boost.Beast and Asio in it: they take half a minute to compile,
// so nothing else of teejet-web includes them.

#include "server.hpp"

#include <openssl/err.h>
#include <openssl/ssl.h>

#include <algorithm>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/write.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#include "beast_transport.hpp"
#include "dashboard_json.hpp"
#include "page_admission.hpp"
#include "page_files.hpp"
#include "page_outbox.hpp"
#include "request_guard.hpp"
#include "token_file.hpp"
#include "token_guard.hpp"

namespace teejet::web {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using TlsStream = beast::ssl_stream<beast::tcp_stream>;
using namespace std::chrono_literals;

// Open connections of every kind (requests, keep-alive, pages). At the cap a new connection is
// closed at accept: the ones open keep their service, and each of them times out on its own.
constexpr std::size_t kMaxConnections = 256;
// A request line and headers beyond this are answered 431 and closed; no request has a body.
constexpr std::uint32_t kMaxHeaderBytes = 8 * 1024;
// From accept, or from the previous response of a keep-alive connection, to a whole request's
// headers: both the idle keep-alive timeout and the end of a request dribbled byte by byte. On a
// TLS server the same bounds the handshake.
constexpr auto kRequestDeadline = 10s;
// A WebSocket's opening and closing handshakes.
constexpr auto kHandshakeTimeout = 10s;
// A page that answers nothing (not even the pings sent after half of it) is closed. Browsers
// answer pings by themselves. TEEJET_WEB_PAGE_IDLE_S sets it for the tests.
constexpr auto kPageIdleTimeout = 30s;
constexpr int kPageSendBuffer = 64 * 1024;

using transport::ConnectionSlot;
using transport::endpoint;
using transport::header;
using transport::Request;
using transport::SentIds;
using Response = http::response<http::string_body>;

// The one place where the headers every response carries (the WebSocket's 101 too) are set:
// request_guard's security headers and ours.
template <class Fields>
void set_response_headers(Fields& fields) {
  fields.set(http::field::server, "teejet-web");
  fields.set(http::field::cache_control, "no-store");
  for (const Header& header : kSecurityHeaders) {
    fields.set(beast::string_view(header.name.data(), header.name.size()),
               beast::string_view(header.value.data(), header.value.size()));
  }
}

std::chrono::seconds page_idle_timeout() {
  const char* text = std::getenv("TEEJET_WEB_PAGE_IDLE_S");
  const long seconds = text == nullptr ? 0 : std::strtol(text, nullptr, 10);
  return seconds > 0 ? std::chrono::seconds(seconds) : kPageIdleTimeout;
}

// Plain TCP, or TLS over it, behind one type. Beast's HTTP and WebSocket code is most of this
// file's compile time and is compiled once per stream type it runs on: on this one type it is
// compiled once, and only the reads and writes of bytes below know which stream carries them
// (with a session per stream type, TLS had doubled the file's compile time to 2 minutes).
class ByteStream {
 public:
  using executor_type = beast::tcp_stream::executor_type;

  explicit ByteStream(beast::tcp_stream&& plain)
      : plain_(std::make_unique<beast::tcp_stream>(std::move(plain))) {}
  explicit ByteStream(TlsStream&& tls) : tls_(std::make_unique<TlsStream>(std::move(tls))) {}

  executor_type get_executor() { return tcp().get_executor(); }
  // The TCP stream under it: its deadlines, its socket.
  beast::tcp_stream& tcp() { return plain_ ? *plain_ : beast::get_lowest_layer(*tls_); }

  // What Asio's AsyncReadStream and AsyncWriteStream ask for. A read fills the first buffer
  // that has room; a write sends what fits in kWriteChunk: both may do less than asked, as
  // read_some and write_some may, and Beast's composed operations go on until all is done.
  template <class Buffers, class Handler>
  void async_read_some(const Buffers& buffers, Handler&& handler) {
    asio::mutable_buffer first;
    for (auto it = asio::buffer_sequence_begin(buffers); it != asio::buffer_sequence_end(buffers);
         ++it) {
      if (asio::mutable_buffer(*it).size() > 0) {
        first = *it;
        break;
      }
    }
    read_some(first, Done(std::forward<Handler>(handler)));
  }
  template <class Buffers, class Handler>
  void async_write_some(const Buffers& buffers, Handler&& handler) {
    written_.resize(std::min(asio::buffer_size(buffers), kWriteChunk));
    written_.resize(asio::buffer_copy(asio::buffer(written_), buffers));
    write_some(Done(std::forward<Handler>(handler)));
  }

  // The WebSocket's closing: TLS's close_notify, then the socket's (Beast's teardown of each).
  friend void teardown(beast::role_type role, ByteStream& stream, beast::error_code& error) {
    stream.close_websocket(role, error);
  }
  template <class Handler>
  friend void async_teardown(beast::role_type role, ByteStream& stream, Handler&& handler) {
    stream.async_close_websocket(
        role, Done([done = std::forward<Handler>(handler)](
                       beast::error_code error, std::size_t) mutable { std::move(done)(error); }));
  }
  friend void beast_close_socket(ByteStream& stream) { stream.tcp().close(); }

 private:
  static constexpr std::size_t kWriteChunk = 16 * 1024;

  // A completion handler of any type, called once: the one type the streams below see.
  class Done {
   public:
    template <class Handler>
    explicit Done(Handler&& handler)
        : call_(std::make_unique<Call<std::decay_t<Handler>>>(std::forward<Handler>(handler))) {}
    void operator()(beast::error_code error, std::size_t bytes) {
      const auto call = std::move(call_);
      (*call)(error, bytes);
    }

   private:
    struct Base {
      virtual ~Base() = default;
      virtual void operator()(beast::error_code error, std::size_t bytes) = 0;
    };
    template <class Handler>
    struct Call final : Base {
      template <class H>
      explicit Call(H&& h) : handler(std::forward<H>(h)) {}
      void operator()(beast::error_code error, std::size_t bytes) override {
        std::move(handler)(error, bytes);
      }
      Handler handler;
    };
    std::unique_ptr<Base> call_;
  };

  void read_some(asio::mutable_buffer buffer, Done done);
  void write_some(Done done);
  void close_websocket(beast::role_type role, beast::error_code& error);
  void async_close_websocket(beast::role_type role, Done done);

  std::unique_ptr<beast::tcp_stream> plain_;
  std::unique_ptr<TlsStream> tls_;
  std::vector<char> written_;  // what the write under way sends
};

void ByteStream::read_some(asio::mutable_buffer buffer, Done done) {
  auto complete = [done = std::move(done)](beast::error_code error, std::size_t bytes) mutable {
    done(error, bytes);
  };
  if (tls_) {
    tls_->async_read_some(buffer, std::move(complete));
  } else {
    plain_->async_read_some(buffer, std::move(complete));
  }
}

void ByteStream::write_some(Done done) {
  auto complete = [done = std::move(done)](beast::error_code error, std::size_t bytes) mutable {
    done(error, bytes);
  };
  if (tls_) {
    tls_->async_write_some(asio::buffer(written_), std::move(complete));
  } else {
    plain_->async_write_some(asio::buffer(written_), std::move(complete));
  }
}

// Beast's teardown of each stream is a hidden friend or an overload in websocket, found by
// argument-dependent lookup only from outside ByteStream (whose own members hide the name).
template <class Stream>
void teardown_stream(beast::role_type role, Stream& stream, beast::error_code& error) {
  using websocket::teardown;
  teardown(role, stream, error);
}
template <class Stream, class Handler>
void async_teardown_stream(beast::role_type role, Stream& stream, Handler&& handler) {
  using websocket::async_teardown;
  async_teardown(role, stream, std::forward<Handler>(handler));
}

void ByteStream::close_websocket(beast::role_type role, beast::error_code& error) {
  if (tls_) {
    teardown_stream(role, *tls_, error);
  } else {
    teardown_stream(role, plain_->socket(), error);
  }
}

void ByteStream::async_close_websocket(beast::role_type role, Done done) {
  auto complete = [done = std::move(done)](beast::error_code error) mutable { done(error, 0); };
  if (tls_) {
    async_teardown_stream(role, *tls_, std::move(complete));
  } else {
    async_teardown_stream(role, plain_->socket(), std::move(complete));
  }
}

}  // namespace

struct TlsIdentity {
  asio::ssl::context context{asio::ssl::context::tls_server};
};

Result<std::shared_ptr<TlsIdentity>> load_tls_identity(const std::filesystem::path& cert,
                                                       const std::filesystem::path& key) {
  const auto fail = [](std::string_view option, const std::filesystem::path& file,
                       const std::string& why) {
    return Error{ErrorCode::kInvalidValue, std::string(option) + " " + file.string() + ": " + why};
  };
  if (!std::ifstream(cert)) return fail("--tls-cert", cert, "cannot read it");
  if (const auto problem = owner_only_problem(key)) return fail("--tls-key", key, *problem);
  if (!std::ifstream(key)) return fail("--tls-key", key, "cannot read it");
  auto identity = std::make_shared<TlsIdentity>();
  asio::ssl::context& context = identity->context;
  // TLS 1.2 at least, the server's order of ciphers rather than the client's; no client
  // certificates are asked for (a server context verifies none by default).
  context.set_options(asio::ssl::context::default_workarounds | asio::ssl::context::no_sslv2 |
                      asio::ssl::context::no_sslv3 | asio::ssl::context::no_tlsv1 |
                      asio::ssl::context::no_tlsv1_1 | asio::ssl::context::single_dh_use);
  SSL_CTX_set_min_proto_version(context.native_handle(), TLS1_2_VERSION);
  SSL_CTX_set_options(context.native_handle(), SSL_OP_CIPHER_SERVER_PREFERENCE);
  // An encrypted key would otherwise ask for its passphrase on the terminal: refuse it instead.
  context.set_password_callback(
      [](std::size_t, asio::ssl::context::password_purpose) { return std::string(); });
  beast::error_code error;
  context.use_certificate_chain_file(cert.string(), error);
  if (error) return fail("--tls-cert", cert, "not a PEM certificate (" + error.message() + ")");
  context.use_private_key_file(key.string(), asio::ssl::context::pem, error);
  const bool mismatch = error ? ERR_GET_REASON(static_cast<unsigned long>(error.value())) ==
                                    X509_R_KEY_VALUES_MISMATCH
                              : SSL_CTX_check_private_key(context.native_handle()) != 1;
  if (mismatch) return fail("--tls-key", key, "not the key of --tls-cert " + cert.string());
  if (error) {
    return fail("--tls-key", key, "not an unencrypted PEM private key (" + error.message() + ")");
  }
  return identity;
}

// One open page as the tick sees it, whatever stream it is on. Not in the anonymous namespace:
// Server::Impl holds pointers to it.
class ServedPage {
 public:
  virtual ~ServedPage() = default;
  virtual void deliver(const nlohmann::json& message) = 0;
  UpdateBatcher batcher;
};

struct Server::Impl {
  Impl(const ServerOptions& options, client::ValveView& valve_view, DdsSender& dds_sender,
       PageFiles page_files)
      : policy(options.policy),
        hosts(options.hosts),
        tokens(options.policy.token, [] { return std::chrono::steady_clock::now(); }),
        view(valve_view),
        sender(dds_sender),
        files(std::move(page_files)),
        tls(options.tls) {}

  void accept();
  void feed_pages(const DdsSender::Statuses& statuses, std::uint64_t stamp_ms);
  Response respond(const Request& request) const;

  const CommandPolicy policy;
  const AllowedHosts hosts;
  TokenGuard tokens;  // unused without a token
  client::ValveView& view;
  DdsSender& sender;
  const PageFiles files;
  const std::chrono::seconds page_idle = page_idle_timeout();
  const std::shared_ptr<TlsIdentity> tls;  // none: plain http
  const Scheme scheme = tls ? Scheme::kHttps : Scheme::kHttp;
  // Touched on the I/O thread only. Declared before the io_context: the sessions that its
  // handlers still own when it goes count themselves out of these.
  std::size_t connections = 0;
  std::size_t admitted_pages = 0;  // counted at admission, before the 101 is written
  std::set<ServedPage*> pages;     // those that got their 101, fed by the tick
  std::uint64_t fed_revision = 0;  // of the view, as of the last tick that fed pages
  Targets fed_targets;             // as of that tick
  bool said_full = false;
  asio::io_context io{1};
  tcp::acceptor acceptor{io};
  asio::steady_timer accept_retry{io};
  asio::executor_work_guard<asio::io_context::executor_type> work{io.get_executor()};
  std::thread thread;
  // The pages' messages (commands, layout changes): Session::on_read.
  asio::io_context commands{1};
  asio::executor_work_guard<asio::io_context::executor_type> commands_work{commands.get_executor()};
  std::thread commands_thread;
};

namespace {

// A page's WebSocket. Admitted already: it holds one of kMaxPages from its construction to its
// destruction.
class PageSession final : public ServedPage, public std::enable_shared_from_this<PageSession> {
 public:
  PageSession(Server::Impl& server, ByteStream&& stream, ConnectionSlot slot)
      : server_(server), socket_(std::move(stream)), slot_(std::move(slot)) {
    ++server_.admitted_pages;
    beast::error_code ignored;
    tcp::socket& socket = socket_.next_layer().tcp().socket();
    peer_ = socket.remote_endpoint(ignored);
    // Loopback's send buffer grows to megabytes: a page that stopped reading would take tens of
    // thousands of messages to show it in its outbox; a longer message only takes more writes.
    socket.set_option(asio::socket_base::send_buffer_size(kPageSendBuffer), ignored);
  }
  ~PageSession() override {
    server_.pages.erase(this);
    server_.tokens.forget(token_key());
    --server_.admitted_pages;
  }

  void accept(Request request) {
    socket_.set_option(websocket::stream_base::timeout{kHandshakeTimeout, server_.page_idle, true});
    socket_.set_option(websocket::stream_base::decorator(
        [](websocket::response_type& response) { set_response_headers(response); }));
    // A longer message is refused from its frame header, before any of it is buffered (1009).
    socket_.read_message_max(kMaxCommandBytes);
    // Each message one frame, as the page and the test clients have always had them.
    socket_.auto_fragment(false);
    socket_.async_accept(request, [self = this->shared_from_this()](beast::error_code error) {
      self->on_accept(error);
    });
  }

  void deliver(const nlohmann::json& message) override {
    if (closed_) return;
    if (outbox_.post(message)) {
      std::cerr << "teejet-web: a page stopped reading (" << kMaxQueuedMessages
                << " messages waiting): dropped\n";
    }
    write_next();
  }

 private:
  void on_accept(beast::error_code error) {
    if (error) return;
    server_.pages.insert(this);
    const DashboardFrame frame = dashboard_frame(server_.view.snapshot(), server_.sender.targets());
    nlohmann::json snapshot = batcher.snapshot(frame);
    snapshot["commands"] = command_policy_json(server_.policy);
    snapshot["protocol"] = page_protocol_json();
    deliver(snapshot);
    read();
  }

  void read() {
    socket_.async_read(input_, [self = this->shared_from_this()](
                                   beast::error_code error, std::size_t) { self->on_read(error); });
  }

  // Beast has checked the frames (masking, RSV bits, opcodes, control frames, fragments) and put
  // a fragmented message together: a protocol error has been answered with close 1002 already.
  void on_read(beast::error_code error) {
    if (error) {
      stop_feeding();
      return;
    }
    if (socket_.got_text()) {
      // Handled on the commands thread, answered back here: a page's first command waits up to
      // 5 s for the gateways to match the command writer, and no other page waits with it.
      // One thread keeps every page's messages in the order they came. The statuses of what
      // was sent wait in the sender until the answer is in the page's outbox: the page matches
      // them to the command_id the answer gives it.
      asio::post(server_.commands, [self = this->shared_from_this(),
                                    text = beast::buffers_to_string(input_.data())]() mutable {
        SentIds sent(self->server_.sender);
        auto answer = self->answer(text, sent);
        auto& io = self->server_.io;
        // The session's last reference goes on the I/O thread, which owns its counters.
        asio::post(io,
                   [self = std::move(self), answer = std::move(answer), sent = std::move(sent)] {
                     self->deliver(answer);
                     self->server_.sender.answered(sent.commands, sent.changes);
                   });
      });
    }
    input_.consume(input_.size());
    read();
  }

  // On the commands thread: reads only what does not change after the page was accepted, the
  // token guard (locked), the view and the sender (both thread-safe).
  nlohmann::json answer(const std::string& text, CommandSender& sender) {
    const auto check_token = [this](std::string_view token) -> std::optional<std::string> {
      const auto answer = server_.tokens.check(token_key(), token);
      if (!answer.log.empty()) {
        std::cerr << "teejet-web: " << answer.log << " (from " << peer_.address().to_string()
                  << " port " << peer_.port() << ")\n";
      }
      if (answer.verdict == TokenGuard::Verdict::kAccepted) return std::nullopt;
      return TokenGuard::reason(answer);
    };
    return handle_page_message(text, server_.sender.directory(), server_.policy, sender,
                               check_token);
  }

  void write_next() {
    auto next = outbox_.start_write();
    if (!next) return;
    auto self = this->shared_from_this();
    if (next->frame == PageOutbox::Frame::kClose) {
      socket_.async_close(websocket::close_code::policy_error,
                          [self](beast::error_code) { self->stop_feeding(); });
      return;
    }
    writing_ = std::move(next->text);
    socket_.text(true);
    socket_.async_write(asio::buffer(writing_), [self](beast::error_code error, std::size_t) {
      if (error) {
        self->stop_feeding();
        return;
      }
      self->outbox_.write_done();
      self->write_next();
    });
  }

  void stop_feeding() {
    closed_ = true;
    server_.pages.erase(this);
  }

  std::uint64_t token_key() const { return reinterpret_cast<std::uintptr_t>(this); }

  Server::Impl& server_;
  websocket::stream<ByteStream> socket_;
  ConnectionSlot slot_;
  beast::flat_buffer input_;
  tcp::endpoint peer_;  // for the log: the socket may be closed by then
  PageOutbox outbox_;
  std::string writing_;  // the text being written: the write reads it until it completes
  bool closed_ = false;
};

// One HTTP connection (over TLS once its handshake is done): requests one after the other
// (keep-alive), until one is an admitted WebSocket upgrade, which goes on as a PageSession.
class HttpSession final : public std::enable_shared_from_this<HttpSession> {
 public:
  // `received`: what was read of the connection already and is not TLS's.
  HttpSession(Server::Impl& server, ByteStream&& stream, ConnectionSlot slot,
              beast::flat_buffer received = {})
      : server_(server),
        stream_(std::move(stream)),
        slot_(std::move(slot)),
        buffer_(std::move(received)) {}

  void read_request() {
    parser_.emplace();
    head_ = false;
    parser_->header_limit(kMaxHeaderBytes);
    stream_.tcp().expires_after(kRequestDeadline);
    http::async_read(stream_, buffer_, *parser_,
                     [self = this->shared_from_this()](beast::error_code error, std::size_t) {
                       self->on_request(error);
                     });
  }

 private:
  void on_request(beast::error_code error) {
    if (error == http::error::header_limit)
      return refuse(http::status::request_header_fields_too_large);
    if (error == http::error::end_of_stream || error == beast::error::timeout) return close();
    if (error) {
      // A body (none is ever wanted), a malformed request line or header.
      if (error.category() == beast::error_code(http::error::bad_target).category()) {
        return refuse(http::status::bad_request);
      }
      return close();
    }
    Request request = parser_->release();
    head_ = request.method() == http::verb::head;
    // Before any route: a name teejet-web does not serve under is a rebound one (request_guard).
    const auto host = header(request, http::field::host);
    if (!host || !host_allowed(*host, server_.hosts)) return write_raw(forbidden_host_answer());
    if (websocket::is_upgrade(request) && request.target() == "/ws")
      return upgrade(std::move(request));
    write(server_.respond(request));
  }

  // The one place a page is admitted.
  void upgrade(Request request) {
    const auto refusal = refuse_page(header(request, http::field::origin), server_.hosts,
                                     server_.scheme, server_.admitted_pages);
    if (refusal) {
      Response response{static_cast<http::status>(refusal->status), request.version()};
      response.set(http::field::content_type, "text/plain; charset=utf-8");
      response.body() = refusal->reason + "\n";
      response.keep_alive(false);
      return write(std::move(response));
    }
    stream_.tcp().expires_never();  // the WebSocket's own timeouts from here
    std::make_shared<PageSession>(server_, std::move(stream_), std::move(slot_))
        ->accept(std::move(request));
  }

  void refuse(http::status status) {
    Response response{status, 11};
    response.set(http::field::content_type, "text/plain; charset=utf-8");
    response.body() = std::string(http::obsolete_reason(status)) + "\n";
    response.keep_alive(false);
    write(std::move(response));
  }

  void write(Response response) {
    set_response_headers(response);
    response.content_length(response.body().size());
    if (head_) response.body().clear();
    response_ = std::move(response);
    http::async_write(stream_, response_,
                      [self = this->shared_from_this()](beast::error_code error, std::size_t) {
                        if (error || !self->response_.keep_alive()) return self->close();
                        self->read_request();
                      });
  }

  // An answer request_guard wrote whole, then the connection closed.
  void write_raw(std::string answer) {
    raw_ = std::move(answer);
    asio::async_write(
        stream_, asio::buffer(raw_),
        [self = this->shared_from_this()](beast::error_code, std::size_t) { self->close(); });
  }

  void close() {
    beast::error_code ignored;
    stream_.tcp().socket().shutdown(tcp::socket::shutdown_send, ignored);
    stream_.tcp().close();
  }

  Server::Impl& server_;
  ByteStream stream_;
  ConnectionSlot slot_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::empty_body>> parser_;
  Response response_;
  std::string raw_;
  bool head_ = false;
};

// A connection to a TLS server before its first byte is known: a TLS handshake goes on as an
// HttpSession over TLS, anything else (a plain http request) is answered 400 and closed.
class TlsDetector final : public std::enable_shared_from_this<TlsDetector> {
 public:
  TlsDetector(Server::Impl& server, beast::tcp_stream&& stream, ConnectionSlot slot)
      : server_(server), stream_(std::move(stream)), slot_(std::move(slot)) {}

  void run() {
    stream_.expires_after(kRequestDeadline);
    beast::async_detect_ssl(stream_, buffer_,
                            [self = shared_from_this()](beast::error_code error, bool tls) {
                              self->on_detect(error, tls);
                            });
  }

 private:
  void on_detect(beast::error_code error, bool tls) {
    if (error) return stream_.close();
    if (tls) return handshake();
    answer_ = plain_http_answer();
    asio::async_write(stream_, asio::buffer(answer_),
                      [self = shared_from_this()](beast::error_code, std::size_t) {
                        beast::error_code ignored;
                        self->stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
                        self->drain();
                      });
  }

  // Under the deadline of a request's headers, which goes on from detection.
  void handshake() {
    tls_.emplace(std::move(stream_), server_.tls->context);
    tls_->async_handshake(asio::ssl::stream_base::server, buffer_.data(),
                          [self = shared_from_this()](beast::error_code error, std::size_t used) {
                            if (error) return beast::get_lowest_layer(*self->tls_).close();
                            self->buffer_.consume(used);
                            std::make_shared<HttpSession>(
                                self->server_, ByteStream(std::move(*self->tls_)),
                                std::move(self->slot_), std::move(self->buffer_))
                                ->read_request();
                          });
  }

  // The rest of the request is read and dropped until the client closes (or the deadline):
  // closing with it unread would reset the connection, and the answer with it.
  void drain() {
    buffer_.clear();
    stream_.async_read_some(buffer_.prepare(4096),
                            [self = shared_from_this()](beast::error_code error, std::size_t) {
                              if (error) return self->stream_.close();
                              self->drain();
                            });
  }

  Server::Impl& server_;
  beast::tcp_stream stream_;
  std::optional<TlsStream> tls_;  // from the handshake on, over stream_
  ConnectionSlot slot_;
  beast::flat_buffer buffer_;
  std::string answer_;
};

}  // namespace

Response Server::Impl::respond(const Request& request) const {
  Response response{http::status::ok, request.version()};
  response.keep_alive(request.keep_alive());
  const auto text = [&](http::status status, std::string body) {
    response.result(status);
    response.set(http::field::content_type, "text/plain; charset=utf-8");
    response.body() = std::move(body);
  };
  if (request.method() != http::verb::get && request.method() != http::verb::head) {
    text(http::status::method_not_allowed, "GET or HEAD only\n");
    response.set(http::field::allow, "GET, HEAD");
    return response;
  }
  const std::string_view target(request.target().data(), request.target().size());
  if (target == "/api/valves") {
    response.set(http::field::content_type, "application/json");
    response.body() = valves_json(view.snapshot(), sender.targets()).dump();
  } else if (const PageFile* file = files.find(target)) {
    response.set(http::field::content_type, file->content_type);
    response.body() = file->body;
  } else {
    text(http::status::not_found, "not found\n");
  }
  return response;
}

void Server::Impl::accept() {
  acceptor.async_accept([this](beast::error_code error, tcp::socket socket) {
    if (error == asio::error::operation_aborted) return;
    if (error) {
      // Out of descriptors, most likely: wait for some to close instead of spinning.
      accept_retry.expires_after(100ms);
      accept_retry.async_wait([this](beast::error_code) { accept(); });
      return;
    }
    if (connections >= kMaxConnections) {
      if (!std::exchange(said_full, true)) {
        std::cerr << "teejet-web: " << kMaxConnections << " connections open: refusing more\n";
      }
      socket.close(error);
    } else {
      said_full = false;
      socket.set_option(tcp::no_delay(true), error);
      if (tls) {
        std::make_shared<TlsDetector>(*this, beast::tcp_stream(std::move(socket)),
                                      ConnectionSlot(connections))
            ->run();
      } else {
        std::make_shared<HttpSession>(*this, ByteStream(beast::tcp_stream(std::move(socket))),
                                      ConnectionSlot(connections))
            ->read_request();
      }
    }
    accept();
  });
}

void Server::Impl::feed_pages(const DdsSender::Statuses& statuses, std::uint64_t stamp_ms) {
  // With no page open (most of a bench's day) there is nobody to build a frame for; a page that
  // opens starts from a snapshot of its own.
  if (pages.empty()) return;
  // Only what changed since the last tick: with 256 valves, building every valve's JSON 25
  // times a second cost a fifth of a core.
  Targets targets = sender.targets();
  const auto changes = view.changes_since(fed_revision, retargeted(fed_targets, targets));
  const DashboardFrame frame =
      dashboard_frame(changes.rows, changes.gateways, changes.places, targets);
  fed_revision = changes.revision;
  fed_targets = std::move(targets);
  for (ServedPage* page : pages) {
    for (const CommandStatus& status : statuses.commands) page->batcher.add_status(status);
    for (const LayoutChangeStatus& status : statuses.layout_changes) {
      page->batcher.add_status(status);
    }
    if (const auto update = page->batcher.tick(frame, stamp_ms)) page->deliver(*update);
  }
}

Result<std::unique_ptr<Server>> Server::start(const ServerOptions& options, client::ValveView& view,
                                              DdsSender& sender) {
  auto files = PageFiles::load(options.www);
  if (!files) return files.error();
  const auto address = endpoint(options.listen);
  if (!address) return address.error();
  auto impl = std::make_unique<Impl>(options, view, sender, std::move(*files));
  if (const auto error = transport::listen_on(impl->acceptor, *address)) {
    return Error{ErrorCode::kUnavailable,
                 "cannot listen on " + options.listen + ": " + error.message()};
  }
  impl->accept();
  impl->thread = std::thread([&io = impl->io] { io.run(); });
  impl->commands_thread = std::thread([&commands = impl->commands] { commands.run(); });
  return std::unique_ptr<Server>(new Server(std::move(impl)));
}

Server::Server(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Server::~Server() {
  // A message being handled may still post its answer: the commands thread ends first.
  impl_->commands.stop();
  impl_->commands_thread.join();
  impl_->io.stop();
  impl_->thread.join();
}

void Server::tick(std::uint64_t stamp_ms) {
  asio::post(impl_->io, [impl = impl_.get(), statuses = impl_->sender.take_statuses(), stamp_ms] {
    impl->feed_pages(statuses, stamp_ms);
  });
}

}  // namespace teejet::web
