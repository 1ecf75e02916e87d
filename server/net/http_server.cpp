#include "net/http_server.hpp"

#include <pthread.h>
#include <sys/socket.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/beast/ssl.hpp>
#include <boost/beast/websocket.hpp>
#include <boost/beast/websocket/ssl.hpp>
#include <openssl/ssl.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <exception>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <tuple>

#include "net/tcp_listen.hpp"
#include "net/tls_server_context.hpp"

namespace haptic::net {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using PlainStream = beast::tcp_stream;
using TlsStream = beast::ssl_stream<beast::tcp_stream>;

/// A client's unread messages past which its WebSocket closes (its handler is not reading).
constexpr std::size_t kMaxUnreadMessages = 16;
/// A WebSocket silent this long is pinged; one that answers nothing in as long again is closed.
constexpr std::chrono::seconds kWebSocketIdle{15};

/// How long accepting pauses when the process is out of descriptors.
constexpr std::chrono::milliseconds kAcceptPause{100};

std::string lower(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string_view trim(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t' || text.back() == '\r')) {
    text.remove_suffix(1);
  }
  return text;
}

/// A head Beast has parsed, as the handler sees it; "" or why it is refused (400).
std::string to_request(const http::request_header<>& head, HttpRequest& out) {
  out = HttpRequest{};
  const auto method = head.method_string();
  const auto target = head.target();
  out.method.assign(method.data(), method.size());
  out.target.assign(target.data(), target.size());
  out.version = head.version() == 11 ? "HTTP/1.1" : "HTTP/1.0";
  if (head.version() != 11 && head.version() != 10) {
    return "only HTTP/1.0 and HTTP/1.1 are served, got HTTP/" + std::to_string(head.version() / 10) +
           "." + std::to_string(head.version() % 10);
  }
  if (out.target.empty() || out.target.front() != '/') {
    return "the target must be a path starting with '/', got '" + out.target.substr(0, 200) + "'";
  }
  out.path = out.target.substr(0, out.target.find('?'));
  for (const auto& field : head) {
    const auto name = field.name_string();
    const auto value = field.value();
    out.headers[lower({name.data(), name.size()})] = std::string(trim({value.data(), value.size()}));
  }
  const std::string* connection = out.header("connection");
  const std::string token = connection != nullptr ? lower(*connection) : std::string();
  out.keep_alive = head.version() == 11 ? token.find("close") == std::string::npos
                                        : token.find("keep-alive") != std::string::npos;
  return {};
}

/// Beast's parser error for a request, as a 400 says it: what the client should have sent, and
/// Beast's own word for what it found.
std::string parse_error(const beast::error_code& error) {
  std::string what = "the request is not HTTP/1.x";
  if (error == http::error::bad_method || error == http::error::bad_target ||
      error == http::error::bad_version) {
    what = "the request line must be 'METHOD /path HTTP/1.x'";
  } else if (error == http::error::bad_field || error == http::error::bad_value) {
    what = "a header line must be 'Name: value'";
  } else if (error == http::error::bad_line_ending) {
    what = "every line must end in CR LF";
  } else if (error == http::error::bad_content_length || error == http::error::bad_transfer_encoding ||
             error == http::error::bad_chunk || error == http::error::bad_chunk_extension) {
    what = "the body's framing is not valid";
  }
  return what + " (" + error.message() + ")";
}

}  // namespace

std::string parse_request_head(std::string_view head, HttpRequest& out) {
  out = HttpRequest{};
  http::request_parser<http::empty_body> parser;
  parser.header_limit(static_cast<std::uint32_t>(std::min<std::size_t>(head.size() + 4, UINT32_MAX)));
  parser.eager(false);
  const std::string whole = std::string(head) + "\r\n\r\n";
  beast::error_code error;
  parser.put(asio::buffer(whole), error);
  if (error == http::error::need_more || (!error && !parser.is_header_done())) {
    return "the request head is not whole";
  }
  if (error) return parse_error(error);
  return to_request(parser.get().base(), out);
}

/// What the I/O thread keeps of every connection, plain or TLS, a request's or a WebSocket's.
struct HttpServer::Connection {
  explicit Connection(std::string peer) : host(std::move(peer)) {}
  virtual ~Connection() = default;
  std::string host;
  std::chrono::steady_clock::time_point accepted_at = std::chrono::steady_clock::now();
  std::uint64_t answered = 0;  // replies queued on it: its progress, with received
  std::size_t received = 0;    // bytes of the request being read
  bool busy = false;           // a request handled or a reply written: not displaced then
  /// Ends it now, on the I/O thread.
  virtual void end() = 0;
};

/// Everything that runs on the I/O thread, and the handler threads beside it.
struct HttpServer::Impl {
  explicit Impl(HttpServer& owner) : server(owner) {}

  HttpServer& server;
  Handler handler;
  asio::io_context io{1};
  asio::io_context handlers;  // the handler threads run this
  std::optional<asio::executor_work_guard<asio::io_context::executor_type>> handlers_work;
  std::vector<std::unique_ptr<tcp::acceptor>> acceptors;
  asio::steady_timer accept_pause{io};
  std::vector<Connection*> sessions;  // open ones, on the I/O thread only
  std::optional<asio::ssl::context> tls;  // with TLS: the server's context
  std::thread io_thread;
  std::vector<std::thread> handler_threads;
  UpgradeCheck upgrade_check;
  WebSocketHandler websocket_handler;
  std::vector<Connection*> websockets;  // open ones, on the I/O thread only
  // WebSocket handlers running (each on a thread of its own): stop() waits for them to return.
  std::mutex websocket_threads_mutex;
  std::condition_variable websocket_threads_done;
  std::size_t websocket_threads = 0;

  void accept(tcp::acceptor& acceptor);
  void accepted(tcp::socket socket);
  /// Makes room for a connection from `host`, displacing another host's if need be (HttpLimits);
  /// "" when there is room, else the share that was met, for the 503.
  std::string make_room(const std::string& host);
};

/// One WebSocket connection: its reads and writes on the I/O thread, its handler on a thread of
/// its own, the two meeting in the inbox and the outbox.
template <class Stream>
struct HttpServer::WebSocketSession : Connection,
                                      WebSocketChannel,
                                      std::enable_shared_from_this<HttpServer::WebSocketSession<Stream>> {
  using std::enable_shared_from_this<WebSocketSession<Stream>>::shared_from_this;

  WebSocketSession(Impl& owner, Stream stream, std::string peer)
      : Connection(std::move(peer)), impl(owner), ws(std::move(stream)) {}

  Impl& impl;
  websocket::stream<Stream> ws;
  beast::flat_buffer read_buffer;
  std::deque<std::pair<std::string, bool>> outbox;  // I/O thread
  bool writing = false;                              // I/O thread
  std::optional<websocket::close_reason> close_pending;  // I/O thread: after the outbox
  bool finished = false;                             // I/O thread
  std::atomic<std::size_t> queued_bytes{0};
  std::atomic<bool> closing{false};
  std::atomic<bool> closed_{false};
  std::mutex inbox_mutex;
  std::condition_variable inbox_ready;
  std::deque<std::string> inbox;

  const HttpLimits& limits() const { return impl.server.limits_; }

  void accept(http::request<http::string_body> request, const HttpRequest& seen) {
    websocket::stream_base::timeout timeouts;
    timeouts.handshake_timeout = limits().timeout;
    timeouts.idle_timeout = kWebSocketIdle;
    timeouts.keep_alive_pings = true;
    ws.set_option(timeouts);
    ws.read_message_max(limits().max_websocket_message_bytes);
    ws.async_accept(request, [self = shared_from_this(), seen](beast::error_code error) {
      if (error) {
        self->finish();
        return;
      }
      self->run_handler(seen);
      self->read();
    });
  }

  void run_handler(const HttpRequest& request) {
    {
      std::lock_guard lock(impl.websocket_threads_mutex);
      ++impl.websocket_threads;
    }
    std::thread([self = shared_from_this(), request]() mutable {
      ::pthread_setname_np(::pthread_self(), ("ws-" + self->impl.server.name_).substr(0, 15).c_str());
      try {
        self->impl.websocket_handler(request, *self);
      } catch (...) {
        // A handler's fault ends its connection, never the server.
      }
      self->close(1000, "");
      Impl& owner = self->impl;
      self.reset();  // before stop() may see this thread done and destroy what the session uses
      std::lock_guard lock(owner.websocket_threads_mutex);
      --owner.websocket_threads;
      owner.websocket_threads_done.notify_all();  // under the lock: stop() cannot have returned yet
    }).detach();
  }

  void read() {
    ws.async_read(read_buffer, [self = shared_from_this()](beast::error_code error, std::size_t) {
      if (error) {
        self->finish();
        return;
      }
      std::string message = beast::buffers_to_string(self->read_buffer.data());
      self->read_buffer.consume(self->read_buffer.size());
      bool overflow = false;
      {
        std::lock_guard lock(self->inbox_mutex);
        overflow = self->inbox.size() >= kMaxUnreadMessages;
        if (!overflow) self->inbox.push_back(std::move(message));
      }
      self->inbox_ready.notify_all();
      if (overflow) {
        self->close_now(websocket::close_reason(
            websocket::close_code::policy_error,
            "more than " + std::to_string(kMaxUnreadMessages) + " messages unread"));
        return;
      }
      self->read();
    });
  }

  bool send(std::string message, bool binary) override {
    if (closing.load() || closed_.load()) return false;
    const std::size_t queued = queued_bytes.fetch_add(message.size()) + message.size();
    if (queued > limits().max_websocket_queue_bytes) {
      close(static_cast<std::uint16_t>(websocket::close_code::policy_error),
            "the client reads too slowly: " + std::to_string(queued) + " bytes waiting");
      return false;
    }
    asio::post(impl.io, [self = shared_from_this(), message = std::move(message), binary]() mutable {
      if (self->finished) return;
      self->outbox.emplace_back(std::move(message), binary);
      if (!self->writing) self->write_next();
    });
    return true;
  }

  void write_next() {
    writing = true;
    ws.binary(outbox.front().second);
    ws.async_write(asio::buffer(outbox.front().first),
                   [self = shared_from_this()](beast::error_code error, std::size_t) {
                     self->queued_bytes.fetch_sub(self->outbox.front().first.size());
                     self->outbox.pop_front();
                     self->writing = false;
                     if (error) {
                       self->finish();
                       return;
                     }
                     if (!self->outbox.empty()) {
                       self->write_next();
                     } else if (self->close_pending) {
                       self->close_now(*self->close_pending);
                     }
                   });
  }

  std::optional<std::string> receive(std::chrono::milliseconds timeout) override {
    std::unique_lock lock(inbox_mutex);
    inbox_ready.wait_for(lock, timeout, [this] { return !inbox.empty() || closed_.load(); });
    if (inbox.empty()) return std::nullopt;
    std::string message = std::move(inbox.front());
    inbox.pop_front();
    return message;
  }

  bool closed() const override { return closed_.load() || closing.load(); }

  void close(std::uint16_t code, std::string reason) override {
    if (closing.exchange(true)) return;
    if (reason.size() > 123) reason.resize(123);  // a close frame's reason: 123 bytes at most
    asio::post(impl.io, [self = shared_from_this(), code, reason = std::move(reason)] {
      if (self->finished) return;
      websocket::close_reason why(static_cast<websocket::close_code>(code), reason);
      if (self->writing) {
        self->close_pending = why;  // what is queued goes first
      } else {
        self->close_now(why);
      }
    });
  }

  /// On the I/O thread: the close handshake, then the end.
  void close_now(const websocket::close_reason& why) {
    closing.store(true);
    ws.async_close(why, [self = shared_from_this()](beast::error_code) { self->finish(); });
  }

  void end() override { finish(); }

  /// On the I/O thread: the connection is over.
  void finish() {
    if (finished) return;
    finished = true;
    closed_.store(true);
    inbox_ready.notify_all();
    beast::error_code ignored;
    beast::get_lowest_layer(ws).socket().close(ignored);
    std::erase(impl.websockets, this);
    impl.server.websockets_.fetch_sub(1, std::memory_order_relaxed);
  }
};

/// One connection: a request read, handled, its reply written; then the next.
template <class Stream>
struct HttpServer::Session : Connection, std::enable_shared_from_this<HttpServer::Session<Stream>> {
  using std::enable_shared_from_this<Session<Stream>>::shared_from_this;
  static constexpr bool kTls = std::is_same_v<Stream, TlsStream>;

  Session(Impl& owner, Stream connection, std::string peer)
      : Connection(std::move(peer)), impl(owner), stream(std::move(connection)) {}

  Impl& impl;
  Stream stream;
  beast::flat_buffer buffer;
  std::optional<http::request_parser<http::string_body>> parser;
  http::response<http::string_body> response;
  std::optional<http::response_serializer<http::string_body>> serializer;
  bool closed = false;

  void end() override { close(); }

  /// With TLS, the handshake first, within the timeout; then the requests.
  void start() {
    if constexpr (kTls) {
      beast::get_lowest_layer(stream).expires_after(limits().timeout);
      stream.async_handshake(asio::ssl::stream_base::server,
                             [self = shared_from_this()](beast::error_code error) {
                               if (self->closed) return;
                               if (error) {
                                 self->impl.server.tls_failed_.fetch_add(1, std::memory_order_relaxed);
                                 self->close();
                                 return;
                               }
                               self->read_next();
                             });
    } else {
      read_next();
    }
  }

  const HttpLimits& limits() const { return impl.server.limits_; }
  const std::string& name() const { return impl.server.name_; }

  void read_next() {
    parser.emplace();
    parser->header_limit(static_cast<std::uint32_t>(limits().max_request_bytes));
    parser->body_limit(limits().max_body_bytes);
    received = 0;
    busy = false;
    // The whole request within the timeout of the reply before it (or of the accept).
    beast::get_lowest_layer(stream).expires_after(limits().timeout);
    read_some();
  }

  void read_some() {
    http::async_read_some(stream, buffer, *parser,
                          [self = shared_from_this()](beast::error_code error, std::size_t bytes) {
                            self->on_read(error, bytes);
                          });
  }

  void on_read(beast::error_code error, std::size_t bytes) {
    if (closed) return;
    received += bytes;
    if (error == http::error::header_limit) {
      reply(HttpResponse::text(431, "hapticd " + name() + ": the request head is longer than " +
                                        std::to_string(limits().max_request_bytes) + " bytes\n"),
            false, false);
      return;
    }
    if (error == http::error::body_limit) {
      reply(HttpResponse::text(413, "hapticd " + name() + ": " +
                                        (limits().max_body_bytes == 0
                                             ? std::string("this endpoint takes no request body")
                                             : "the request body is longer than " +
                                                   std::to_string(limits().max_body_bytes) + " bytes") +
                                        "\n"),
            false, false);
      return;
    }
    if (error == beast::error::timeout) {
      impl.server.timeouts_.fetch_add(1, std::memory_order_relaxed);
      close();
      return;
    }
    if (error == http::error::end_of_stream || error == asio::error::eof ||
        error == asio::error::connection_reset || error == asio::error::operation_aborted) {
      close();
      return;
    }
    if (error && error.category() == http::make_error_code(http::error::bad_target).category()) {
      // Beast's parser refused what arrived.
      reply(HttpResponse::text(400, "hapticd " + name() + ": " + parse_error(error) + "\n"), false, false);
      return;
    }
    if (error) {
      close();
      return;
    }
    if (!parser->is_done()) {
      read_some();
      return;
    }
    beast::get_lowest_layer(stream).expires_never();  // the handler may take its time; the next limit is on the reply
    HttpRequest request;
    const std::string refused = to_request(parser->get().base(), request);
    request.peer = host;
    if (!refused.empty()) {
      reply(HttpResponse::text(400, "hapticd " + name() + ": " + refused + "\n"), false, false);
      return;
    }
    if (impl.websocket_handler && websocket::is_upgrade(parser->get())) {
      upgrade(std::move(request));
      return;
    }
    request.body = std::move(parser->get().body());
    const auto& methods = limits().methods;
    if (std::find(methods.begin(), methods.end(), request.method) == methods.end()) {
      std::string allow;
      for (const std::string& method : methods) allow += (allow.empty() ? "" : ", ") + method;
      HttpResponse refusal =
          HttpResponse::text(405, "hapticd " + name() + ": " + request.method + " is not served here (" +
                                      allow + " only)\n");
      refusal.headers.emplace_back("Allow", allow);
      reply(refusal, false, false);
      return;
    }
    busy = true;
    asio::post(impl.handlers, [self = shared_from_this(), request = std::move(request)]() mutable {
      HttpResponse handled;
      try {
        handled = self->impl.handler(request);
      } catch (const std::exception& e) {
        handled = HttpResponse::text(500, "hapticd " + self->name() + ": " + e.what() + "\n");
      } catch (...) {
        handled = HttpResponse::text(500, "hapticd " + self->name() + ": the handler failed\n");
      }
      const bool head_only = request.method == "HEAD";
      const bool keep_alive = request.keep_alive;
      asio::post(self->impl.io, [self, handled = std::move(handled), head_only, keep_alive]() mutable {
        if (!self->closed) self->reply(std::move(handled), head_only, keep_alive);
      });
    });
  }

  /// A WebSocket upgrade: refused (as the check answers, or 503 past max_websockets), or the
  /// connection becomes a WebSocketSession, this session ending without closing it.
  void upgrade(HttpRequest request) {
    if (auto refusal = impl.upgrade_check(request)) {
      reply(std::move(*refusal), false, false);
      return;
    }
    if (impl.websockets.size() >= limits().max_websockets) {
      HttpResponse full = HttpResponse::text(
          503, "hapticd " + name() + ": " + std::to_string(limits().max_websockets) +
                   " WebSocket connections are open, the most this endpoint holds\n");
      full.headers.emplace_back("Retry-After", "1");
      reply(std::move(full), false, false);
      return;
    }
    beast::get_lowest_layer(stream).expires_never();  // the WebSocket keeps its own timeouts
    auto channel = std::make_shared<WebSocketSession<Stream>>(impl, std::move(stream), host);
    closed = true;
    std::erase(impl.sessions, this);
    impl.websockets.push_back(channel.get());
    impl.server.websockets_.fetch_add(1, std::memory_order_relaxed);
    channel->accept(parser->release(), request);
  }

  /// Writes `reply` (its head alone for HEAD, with the body's length); then reads the next
  /// request, or closes.
  void reply(HttpResponse reply, bool head_only, bool keep_alive) {
    busy = true;
    response = {};
    response.version(11);
    response.result(static_cast<unsigned>(reply.status));
    response.set(http::field::content_type, reply.content_type);
    // Every body is what its Content-Type says: an error line that echoes a path or a Host is
    // never taken for a page.
    response.set("X-Content-Type-Options", "nosniff");
    for (const auto& [field, value] : reply.headers) response.insert(field, value);
    response.keep_alive(keep_alive);
    // Said either way (Beast leaves out HTTP/1.1's default): a client need not know the default.
    response.set(http::field::connection, keep_alive ? "keep-alive" : "close");
    // How long a kept connection waits for its next request (HttpLimits::timeout, whole seconds
    // down): a client that kept it longer would send into a connection the server is closing,
    // and see "other side closed" (Node's fetch keeps one 4 s unless told; told, it keeps it the
    // hint less 2 s).
    const auto idle_s = std::chrono::duration_cast<std::chrono::seconds>(limits().timeout).count();
    if (keep_alive && idle_s >= 1) response.set("Keep-Alive", "timeout=" + std::to_string(idle_s));
    response.content_length(reply.body.size());
    if (!head_only) response.body() = std::move(reply.body);
    ++answered;
    impl.server.replies_.fetch_add(1, std::memory_order_relaxed);
    serializer.emplace(response);
    write_some();
  }

  void write_some() {
    // The limit is on a reader that stops, not on a large reply read slowly: each piece renews it.
    beast::get_lowest_layer(stream).expires_after(limits().timeout);
    http::async_write_some(stream, *serializer,
                           [self = shared_from_this()](beast::error_code error, std::size_t) {
                             self->on_written(error);
                           });
  }

  void on_written(beast::error_code error) {
    if (closed) return;
    if (error == beast::error::timeout) impl.server.timeouts_.fetch_add(1, std::memory_order_relaxed);
    if (error) {
      close();
      return;
    }
    if (!serializer->is_done()) {
      write_some();
      return;
    }
    const bool keep_alive = response.keep_alive();
    serializer.reset();
    if (!keep_alive) {
      close();
      return;
    }
    read_next();
  }

  void close() {
    if (closed) return;
    closed = true;
    beast::error_code ignored;
    beast::get_lowest_layer(stream).socket().shutdown(tcp::socket::shutdown_send, ignored);
    beast::get_lowest_layer(stream).socket().close(ignored);
    std::erase(impl.sessions, this);
  }
};

void HttpServer::Impl::accept(tcp::acceptor& acceptor) {
  acceptor.async_accept(io, [this, &acceptor](beast::error_code error, tcp::socket socket) {
    if (error == asio::error::operation_aborted) return;
    if (error == asio::error::no_descriptors || error == asio::error::no_buffer_space ||
        error == asio::error::no_memory || error.value() == ENFILE) {
      // Out of descriptors, a listener stays readable: wait rather than spin on it.
      accept_pause.expires_after(kAcceptPause);
      accept_pause.async_wait([this, &acceptor](beast::error_code waited) {
        if (!waited) accept(acceptor);
      });
      return;
    }
    if (!error) accepted(std::move(socket));
    accept(acceptor);
  });
}

void HttpServer::Impl::accepted(tcp::socket socket) {
  sockaddr_storage peer{};
  socklen_t length = sizeof peer;
  const int fd = socket.native_handle();
  const std::string host =
      ::getpeername(fd, reinterpret_cast<sockaddr*>(&peer), &length) == 0 ? host_of_peer(peer, length) : "";
  if (const std::string share = make_room(host); !share.empty()) {
    server.refused_.fetch_add(1, std::memory_order_relaxed);  // counted before the peer sees the close
    // Said in one try, never waited for: the refusal names the share it met.
    const std::string why = "hapticd " + server.name_ + ": " + share + "\n";
    const std::string reply = "HTTP/1.1 503 Service Unavailable\r\nContent-Type: text/plain; "
                              "charset=utf-8\r\nContent-Length: " + std::to_string(why.size()) +
                              "\r\nConnection: close\r\nRetry-After: 1\r\n\r\n" + why;
    (void)::send(fd, reply.data(), reply.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
    beast::error_code ignored;
    socket.close(ignored);
    return;
  }
  if (tls) {
    auto session = std::make_shared<Session<TlsStream>>(*this, TlsStream(PlainStream(std::move(socket)), *tls), host);
    sessions.push_back(session.get());
    session->start();
  } else {
    auto session = std::make_shared<Session<PlainStream>>(*this, PlainStream(std::move(socket)), host);
    sessions.push_back(session.get());
    session->start();
  }
}

std::string HttpServer::Impl::make_room(const std::string& host) {
  const HttpLimits& limits = server.limits_;
  std::map<std::string, std::size_t> per_host;
  for (const Connection* s : sessions) ++per_host[s->host];
  for (const Connection* w : websockets) ++per_host[w->host];  // counted, never displaced
  const std::size_t from_host = per_host[host];
  if (from_host >= limits.max_connections_per_peer) {
    return "this host holds " + std::to_string(limits.max_connections_per_peer) +
           " connections, the most one host may";
  }
  if (sessions.size() < limits.max_connections) return {};
  // Full: the least progress among the connections of hosts holding more than this one's, and
  // not busy with a request (its client is waiting for the reply).
  Connection* victim = nullptr;
  const auto progress = [](const Connection& s) { return std::tuple(s.answered, s.received, s.accepted_at); };
  for (Connection* s : sessions) {
    if (s->busy || per_host[s->host] <= from_host + 1) continue;
    if (victim == nullptr || progress(*s) < progress(*victim)) victim = s;
  }
  if (victim == nullptr) {
    return "the endpoint holds " + std::to_string(limits.max_connections) + " connections, its most";
  }
  server.evicted_.fetch_add(1, std::memory_order_relaxed);  // counted before the peer sees the close
  victim->end();
  return {};
}

HttpServer::HttpServer(std::string name, HttpLimits limits) : name_(std::move(name)), limits_(std::move(limits)) {
  impl_ = std::make_unique<Impl>(*this);
}

HttpServer::~HttpServer() { stop(); }

void HttpServer::bind(const std::string& address, const std::string& field) {
  ListeningSockets sockets = listen_tcp(address, name_, field);
  port_ = sockets.port;
  for (const int fd : sockets.fds) {
    sockaddr_storage local{};
    socklen_t length = sizeof local;
    ::getsockname(fd, reinterpret_cast<sockaddr*>(&local), &length);
    auto acceptor = std::make_unique<tcp::acceptor>(impl_->io);
    acceptor->assign(local.ss_family == AF_INET6 ? tcp::v6() : tcp::v4(), fd);
    impl_->acceptors.push_back(std::move(acceptor));
  }
}

void HttpServer::use_tls(std::shared_ptr<const TlsServerContext> tls) {
  // Asio's context takes a reference of its own to the one the control plane's TLS is set from.
  SSL_CTX_up_ref(tls->native());
  impl_->tls.emplace(tls->native());
}

void HttpServer::serve_websockets(UpgradeCheck check, WebSocketHandler handler) {
  impl_->upgrade_check = std::move(check);
  impl_->websocket_handler = std::move(handler);
}

void HttpServer::start(Handler handler) {
  impl_->handler = std::move(handler);
  for (auto& acceptor : impl_->acceptors) impl_->accept(*acceptor);
  impl_->handlers_work.emplace(impl_->handlers.get_executor());
  for (std::size_t i = 0; i < std::max<std::size_t>(1, limits_.handler_threads); ++i) {
    impl_->handler_threads.emplace_back([this] {
      ::pthread_setname_np(::pthread_self(), ("http-" + name_ + "-h").substr(0, 15).c_str());
      impl_->handlers.run();
    });
  }
  // "http-viewer", "http-metrics": top -H and /proc tell the endpoints' threads apart.
  impl_->io_thread = std::thread([this] {
    ::pthread_setname_np(::pthread_self(), ("http-" + name_).substr(0, 15).c_str());
    impl_->io.run();
  });
}

void HttpServer::stop() {
  // The listeners and every connection close on the I/O thread, which then ends; what the closes
  // leave pending (their aborted reads and writes) goes with the context.
  if (impl_->io_thread.joinable()) {
    asio::post(impl_->io, [impl = impl_.get()] {
      beast::error_code ignored;
      for (auto& acceptor : impl->acceptors) acceptor->close(ignored);
      impl->accept_pause.cancel();
      const std::vector<Connection*> open = impl->sessions;
      for (Connection* session : open) session->end();
      const std::vector<Connection*> sockets = impl->websockets;
      for (Connection* socket : sockets) socket->end();
      impl->io.stop();
    });
    impl_->io_thread.join();
  }
  {
    // Every WebSocket's handler sees its connection closed and returns.
    std::unique_lock lock(impl_->websocket_threads_mutex);
    impl_->websocket_threads_done.wait(lock, [this] { return impl_->websocket_threads == 0; });
  }
  impl_->handlers_work.reset();
  impl_->handlers.stop();
  for (std::thread& thread : impl_->handler_threads) thread.join();
  impl_->handler_threads.clear();
  // Every connection was ended on the I/O thread; what they left pending goes with the contexts.
  impl_->acceptors.clear();
}

}  // namespace haptic::net
