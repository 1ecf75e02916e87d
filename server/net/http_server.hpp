#pragma once
// A minimal HTTP/1.1 server on its own thread, for the metrics endpoint and the web viewer: GET
// and HEAD only, no request bodies, keep-alive, one poll loop over every connection. Connections
// are capped; each must send a whole request head within a timeout of its previous reply (or of
// its accept) and take each reply within the same timeout, so a stalled or slow client cannot hold
// the endpoint, and the others are served meanwhile. The handler runs on this thread. Never
// touches the loop.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

namespace haptic::net {

/// One request's head, as parse_request_head read it.
struct HttpRequest {
  std::string method;                          // "GET", "HEAD", ... as sent
  std::string target;                          // "/api/scene?x=1"
  std::string path;                            // the target without its query: "/api/scene"
  std::string version;                         // "HTTP/1.1" or "HTTP/1.0"
  std::map<std::string, std::string> headers;  // names in lower case, values trimmed
  bool keep_alive = false;                     // 1.1 without "Connection: close", or 1.0 with keep-alive
  std::string peer;                            // the client's host (peer_host()'s form)

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

/// Parses a request head (request line and header lines, without the blank line that ends it).
/// Returns "" or what is wrong with it, for a 400's message.
std::string parse_request_head(std::string_view head, HttpRequest& out);

/// The reply's bytes: status line, Content-Type, Content-Length, Connection, the extra headers and,
/// unless `head_only` (a HEAD request), the body.
std::string format_response(const HttpResponse& response, bool head_only, bool keep_alive);

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
};

class HttpServer {
 public:
  using Handler = std::function<HttpResponse(const HttpRequest&)>;

  /// `name` says whose endpoint this is in error messages ("metrics", "viewer").
  explicit HttpServer(std::string name, HttpLimits limits = {});
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  /// Listens on "host:port" (port 0 picks one). Throws std::runtime_error naming `field` or what
  /// failed.
  void bind(const std::string& address, const std::string& field);
  std::uint16_t port() const { return port_; }

  /// Serves until stop(). A method other than GET or HEAD is answered 405 before `handler` sees
  /// it; a head that does not parse, 400 with the reason. An exception from `handler` is a 500.
  void start(Handler handler);
  void stop();

  /// Replies sent, and connections closed at once because a cap was reached.
  std::uint64_t replies() const { return replies_.load(std::memory_order_relaxed); }
  std::uint64_t refused() const { return refused_.load(std::memory_order_relaxed); }
  /// Connections closed to make room at max_connections for another host's.
  std::uint64_t evicted() const { return evicted_.load(std::memory_order_relaxed); }
  /// Connections closed because a request head or a reply made no progress within the timeout.
  std::uint64_t timeouts() const { return timeouts_.load(std::memory_order_relaxed); }

 private:
  struct Connection;
  void serve_loop();
  void accept_from(int listening_fd, std::vector<Connection>& connections);
  /// Makes room for a connection from `host`, displacing another host's if need be (HttpLimits);
  /// "" when there is room, else the share that was met, for the 503.
  std::string make_room(const std::string& host, std::vector<Connection>& connections);
  /// Reads what arrived; false when the connection is done with.
  bool receive(Connection& connection);
  /// Queues the reply to the next whole request in the connection's buffer; false when there is
  /// none yet.
  bool answer(Connection& connection);
  /// Sends what is pending; false when the connection is done with.
  bool flush(Connection& connection);

  std::string name_;
  HttpLimits limits_;
  std::vector<int> listening_;
  std::uint16_t port_ = 0;
  Handler handler_;
  std::atomic<bool> stopping_{false};
  // Set when accept ran out of descriptors: the listeners are not polled before then.
  std::chrono::steady_clock::time_point accept_paused_until_{};
  std::atomic<std::uint64_t> replies_{0};
  std::atomic<std::uint64_t> refused_{0};
  std::atomic<std::uint64_t> evicted_{0};
  std::atomic<std::uint64_t> timeouts_{0};
  std::thread thread_;
};

}  // namespace haptic::net
