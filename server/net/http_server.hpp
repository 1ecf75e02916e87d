#pragma once
// The HTTP/1.1 server under the metrics endpoint, the web viewer and the control plane's JSON
// face: Boost.Beast's parser and serializer on Boost.Asio, one I/O thread for every connection,
// the handler on threads of its own (a call that waits, a lockstep Step, holds up no other
// connection's reading or writing). Keep-alive and pipelining (each connection's replies in the
// order of its requests). Connections are capped, in all and per host; each must send a whole
// request within a timeout of its previous reply (or of its accept), and its reply must make
// progress within the same timeout, so a stalled or slow client cannot hold the endpoint, and the
// others are served meanwhile. Never touches the loop.
//
// Why Beast (Debian's libboost-dev, header-only): a maintained HTTP/1.1 parser with limits on the
// head and the body, a serializer that writes a reply piece by piece (a timeout on progress, not
// on the whole reply), WebSocket on the same connections, and TLS through Asio's OpenSSL stream;
// and it compiles as C++20, which websocketpp 0.8 (the Haply driver's) does not.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace haptic::net {

class TlsServerContext;

/// One request's head, as parse_request_head read it.
struct HttpRequest {
  std::string method;                          // "GET", "HEAD", ... as sent
  std::string target;                          // "/api/scene?x=1"
  std::string path;                            // the target without its query: "/api/scene"
  std::string version;                         // "HTTP/1.1" or "HTTP/1.0"
  std::map<std::string, std::string> headers;  // names in lower case, values trimmed
  bool keep_alive = false;                     // 1.1 without "Connection: close", or 1.0 with keep-alive
  std::string peer;                            // the client's host (peer_host()'s form)
  std::string body;                            // as sent (HttpLimits::max_body_bytes at most)

  /// The header's value, or nullptr when it was not sent.
  const std::string* header(const std::string& lower_case_name) const {
    const auto found = headers.find(lower_case_name);
    return found == headers.end() ? nullptr : &found->second;
  }
};

struct HttpResponse {
  int status = 200;
  std::string content_type = "text/plain; charset=utf-8";
  std::string body;
  std::vector<std::pair<std::string, std::string>> headers;  // besides the ones every reply has

  /// A plain-text reply (a refusal's message, say).
  static HttpResponse text(int status, std::string body) {
    HttpResponse response;
    response.status = status;
    response.body = std::move(body);
    return response;
  }
};

/// Parses a request head (request line and header lines, without the blank line that ends it) as
/// the server does: Beast's parser, then the same checks and conversion. Returns "" or what is
/// wrong with it, for a 400's message.
std::string parse_request_head(std::string_view head, HttpRequest& out);

/// A WebSocket connection once its upgrade is accepted, as its handler (on a thread of its own)
/// sees it. Safe to use from any thread.
class WebSocketChannel {
 public:
  virtual ~WebSocketChannel() = default;
  /// Queues a message; false once the connection is closed, or when the client reads so slowly
  /// that HttpLimits::max_websocket_queue_bytes are waiting (the connection is then closed,
  /// saying so: nothing is dropped unseen).
  virtual bool send(std::string message, bool binary) = 0;
  /// The next message from the client, waiting up to `timeout`; nullopt on the timeout or once
  /// the connection is closed.
  virtual std::optional<std::string> receive(std::chrono::milliseconds timeout) = 0;
  virtual bool closed() const = 0;
  /// Closes (a WebSocket close frame with `code` and `reason`, after what is queued).
  virtual void close(std::uint16_t code, std::string reason) = 0;
};

struct HttpLimits {
  // Open at once, in all and from one host. Past the host's share a new connection is accepted
  // and closed at once. At the cap in all, a newcomer from a host holding fewer displaces the
  // connection making the least progress (fewest replies, then fewest bytes of its request so
  // far, then the oldest) of a host holding more; if there is none, the newcomer is closed.
  std::size_t max_connections = 32;
  std::size_t max_connections_per_peer = 8;
  // For each request head to arrive, and for each reply to make progress (a large one read slowly
  // is not cut off; a reader that stops is).
  std::chrono::milliseconds timeout{2000};
  std::size_t max_request_bytes = 8192;     // a longer head is answered 431 and closed
  std::size_t max_body_bytes = 0;           // a longer body is answered 413 and closed
  /// The methods served; any other is answered 405 naming these in Allow.
  std::vector<std::string> methods{"GET", "HEAD"};
  /// Threads that run the handler: the most requests handled at once.
  std::size_t handler_threads = 1;
  /// WebSocket connections open at once (each with a thread of its own), past which an upgrade
  /// is answered 503; a message from a client longer than max_websocket_message_bytes closes its
  /// connection; so does a queue of messages to it longer than max_websocket_queue_bytes.
  std::size_t max_websockets = 64;
  std::size_t max_websocket_message_bytes = 64u << 10;
  std::size_t max_websocket_queue_bytes = 4u << 20;
};

class HttpServer {
 public:
  using Handler = std::function<HttpResponse(const HttpRequest&)>;
  /// For a WebSocket upgrade: nullopt accepts it, a response refuses it (sent as it is). Runs on
  /// the I/O thread: it must be quick (a path, an Origin).
  using UpgradeCheck = std::function<std::optional<HttpResponse>(const HttpRequest&)>;
  /// An accepted WebSocket's life, on a thread of its own; the connection closes when it returns.
  using WebSocketHandler = std::function<void(const HttpRequest&, WebSocketChannel&)>;

  /// `name` says whose endpoint this is in error messages ("metrics", "viewer").
  explicit HttpServer(std::string name, HttpLimits limits = {});
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  /// Listens on "host:port" (port 0 picks one). Throws std::runtime_error naming `field` or what
  /// failed.
  void bind(const std::string& address, const std::string& field);
  std::uint16_t port() const { return port_; }

  /// Serves until stop(). A method not in HttpLimits::methods is answered 405 before `handler`
  /// sees it; a head that does not parse, 400 with the reason. An exception from `handler` is a
  /// 500. `handler` runs on the server's handler threads, several at once when there are several.
  void start(Handler handler);
  /// Serves WebSocket upgrades too (before start()); without, an upgrade is an ordinary request.
  void serve_websockets(UpgradeCheck check, WebSocketHandler handler);
  /// Serves HTTPS only (before start()): the TLS context's certificate, and with its client CA
  /// mutual TLS. A handshake not done within HttpLimits::timeout closes the connection.
  void use_tls(std::shared_ptr<const TlsServerContext> tls);
  /// TLS handshakes that failed (a client without a certificate under mutual TLS, say).
  std::uint64_t tls_failed() const { return tls_failed_.load(std::memory_order_relaxed); }
  /// WebSocket connections open now.
  std::size_t websockets() const { return websockets_.load(std::memory_order_relaxed); }
  /// Stops serving: the listeners and every connection close; waits for handlers running.
  void stop();

  /// Replies sent, and connections closed at once because a cap was reached.
  std::uint64_t replies() const { return replies_.load(std::memory_order_relaxed); }
  std::uint64_t refused() const { return refused_.load(std::memory_order_relaxed); }
  /// Connections closed to make room at max_connections for another host's.
  std::uint64_t evicted() const { return evicted_.load(std::memory_order_relaxed); }
  /// Connections closed because a request head or a reply made no progress within the timeout.
  std::uint64_t timeouts() const { return timeouts_.load(std::memory_order_relaxed); }

 private:
  struct Impl;
  struct Connection;
  template <class Stream>
  struct Session;
  template <class Stream>
  struct WebSocketSession;

  std::string name_;
  HttpLimits limits_;
  std::uint16_t port_ = 0;
  std::atomic<std::uint64_t> replies_{0};
  std::atomic<std::uint64_t> refused_{0};
  std::atomic<std::uint64_t> evicted_{0};
  std::atomic<std::uint64_t> timeouts_{0};
  std::atomic<std::size_t> websockets_{0};
  std::atomic<std::uint64_t> tls_failed_{0};
  std::unique_ptr<Impl> impl_;
};

}  // namespace haptic::net
