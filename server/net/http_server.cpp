#include "net/http_server.hpp"

#include <poll.h>
#include <pthread.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <exception>
#include <map>
#include <tuple>

#include "net/tcp_listen.hpp"

namespace haptic::net {
namespace {

constexpr int kPollMs = 100;  // how often the thread looks for stop() when nothing happens

const char* reason_phrase(int status) {
  switch (status) {
    case 200: return "OK";
    case 400: return "Bad Request";
    case 401: return "Unauthorized";
    case 403: return "Forbidden";
    case 404: return "Not Found";
    case 405: return "Method Not Allowed";
    case 431: return "Request Header Fields Too Large";
    case 500: return "Internal Server Error";
    default: return "Unknown";
  }
}

std::string_view trim(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t' || text.back() == '\r')) {
    text.remove_suffix(1);
  }
  return text;
}

std::string lower(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

/// The end of the head (the index past its blank line) in `buffer`, or npos while incomplete.
/// A bare LF ends lines too.
std::size_t head_end(const std::string& buffer, std::size_t& head_length) {
  const std::size_t crlf = buffer.find("\r\n\r\n");
  const std::size_t lf = buffer.find("\n\n");
  if (crlf != std::string::npos && (lf == std::string::npos || crlf < lf)) {
    head_length = crlf;
    return crlf + 4;
  }
  if (lf != std::string::npos) {
    head_length = lf;
    return lf + 2;
  }
  return std::string::npos;
}

}  // namespace

std::string parse_request_head(std::string_view head, HttpRequest& out) {
  out = HttpRequest{};
  const std::size_t line_end = std::min(head.find('\n'), head.size());
  const std::string_view line = trim(head.substr(0, line_end));
  const std::size_t first_space = line.find(' ');
  const std::size_t second_space =
      first_space == std::string_view::npos ? first_space : line.find(' ', first_space + 1);
  if (second_space == std::string_view::npos || line.find(' ', second_space + 1) != std::string_view::npos) {
    return "the request line must be 'METHOD TARGET HTTP/1.x', got '" + std::string(line.substr(0, 200)) +
           "'";
  }
  out.method = line.substr(0, first_space);
  out.target = line.substr(first_space + 1, second_space - first_space - 1);
  out.version = line.substr(second_space + 1);
  if (out.version != "HTTP/1.1" && out.version != "HTTP/1.0") {
    return "only HTTP/1.0 and HTTP/1.1 are served, got '" + out.version.substr(0, 20) + "'";
  }
  if (out.method.empty() || out.target.empty() || out.target.front() != '/') {
    return "the target must be a path starting with '/', got '" + out.target.substr(0, 200) + "'";
  }
  out.path = out.target.substr(0, out.target.find('?'));
  for (std::size_t at = line_end + 1; at < head.size();) {
    const std::size_t end = std::min(head.find('\n', at), head.size());
    const std::string_view header = trim(head.substr(at, end - at));
    at = end + 1;
    if (header.empty()) continue;
    const std::size_t colon = header.find(':');
    // The name is checked after trimming: a line of "\r: x" would otherwise give an empty one.
    const std::string_view name = colon == std::string_view::npos ? std::string_view() : trim(header.substr(0, colon));
    if (name.empty()) {
      return "a header line must be 'Name: value', got '" + std::string(header.substr(0, 200)) + "'";
    }
    out.headers[lower(name)] = std::string(trim(header.substr(colon + 1)));
  }
  const std::string* connection = out.header("connection");
  const std::string token = connection != nullptr ? lower(*connection) : std::string();
  out.keep_alive = out.version == "HTTP/1.1" ? token.find("close") == std::string::npos
                                             : token.find("keep-alive") != std::string::npos;
  return {};
}

std::string format_response(const HttpResponse& response, bool head_only, bool keep_alive) {
  std::string bytes = "HTTP/1.1 " + std::to_string(response.status) + " " + reason_phrase(response.status) +
                      "\r\nContent-Type: " + response.content_type +
                      "\r\nContent-Length: " + std::to_string(response.body.size()) +
                      "\r\nConnection: " + (keep_alive ? "keep-alive" : "close") +
                      // Every body is what its Content-Type says: an error line that echoes a path
                      // or a Host is never taken for a page.
                      "\r\nX-Content-Type-Options: nosniff\r\n";
  for (const auto& [name, value] : response.headers) bytes += name + ": " + value + "\r\n";
  bytes += "\r\n";
  if (!head_only) bytes += response.body;
  return bytes;
}

struct HttpServer::Connection {
  int fd = -1;
  std::string host;  // the client's
  std::uint64_t answered = 0;  // replies queued on it: its progress, with received.size()
  std::chrono::steady_clock::time_point accepted_at;
  std::string received;
  std::string pending;  // the reply being sent
  std::size_t sent = 0;
  bool close_when_sent = false;
  std::chrono::steady_clock::time_point deadline;
};

HttpServer::HttpServer(std::string name, HttpLimits limits) : name_(std::move(name)), limits_(limits) {}

HttpServer::~HttpServer() { stop(); }

void HttpServer::bind(const std::string& address, const std::string& field) {
  ListeningSockets sockets = listen_tcp(address, name_, field);
  listening_ = std::move(sockets.fds);
  port_ = sockets.port;
}

void HttpServer::start(Handler handler) {
  handler_ = std::move(handler);
  stopping_.store(false);
  thread_ = std::thread([this] { serve_loop(); });
}

void HttpServer::stop() {
  stopping_.store(true);
  if (thread_.joinable()) thread_.join();
  for (const int fd : listening_) ::close(fd);
  listening_.clear();
}

void HttpServer::serve_loop() {
  // "http-viewer", "http-metrics": top -H and /proc tell the endpoints' threads apart.
  ::pthread_setname_np(::pthread_self(), ("http-" + name_).substr(0, 15).c_str());
  std::vector<Connection> connections;
  std::vector<pollfd> polled;
  while (!stopping_.load()) {
    polled.clear();
    // Out of descriptors, a listener stays readable: it is left out until the pause ends rather
    // than waking this thread again at once.
    const bool accepting = std::chrono::steady_clock::now() >= accept_paused_until_;
    for (const int fd : listening_) polled.push_back({fd, static_cast<short>(accepting ? POLLIN : 0), 0});
    auto wake = std::chrono::steady_clock::now() + std::chrono::milliseconds(kPollMs);
    for (const Connection& c : connections) {
      polled.push_back({c.fd, static_cast<short>(c.pending.empty() ? POLLIN : POLLOUT), 0});
      wake = std::min(wake, c.deadline);
    }
    const auto wait = std::chrono::ceil<std::chrono::milliseconds>(wake - std::chrono::steady_clock::now());
    if (::poll(polled.data(), polled.size(), static_cast<int>(std::max<std::int64_t>(0, wait.count()))) < 0 &&
        errno != EINTR) {
      continue;
    }
    // Connections first (their pollfds follow the listeners'), then new ones.
    const std::size_t listeners = listening_.size();
    const auto now = std::chrono::steady_clock::now();
    std::vector<Connection> kept;
    kept.reserve(connections.size());
    for (std::size_t i = 0; i < connections.size(); ++i) {
      Connection& c = connections[i];
      const short events = polled[listeners + i].revents;
      bool alive = true;
      try {
        if ((events & POLLOUT) != 0) alive = flush(c);
        if (alive && (events & (POLLIN | POLLHUP | POLLERR)) != 0 && c.pending.empty()) alive = receive(c);
        // Every whole request already received, in turn (a reply sent at once makes room for the next).
        while (alive && c.pending.empty() && answer(c)) alive = flush(c);
      } catch (const std::exception&) {
        // Out of memory for one reply or one request's bytes: that connection goes, the server
        // (and the device it holds) stays.
        alive = false;
      }
      // A reply queued or sent moved the deadline on; bytes that make no whole request do not.
      if (alive && now >= c.deadline) {
        timeouts_.fetch_add(1, std::memory_order_relaxed);
        alive = false;
      }
      if (alive) {
        kept.push_back(std::move(c));
      } else {
        ::close(c.fd);
      }
    }
    connections = std::move(kept);
    for (std::size_t i = 0; i < listeners; ++i) {
      if ((polled[i].revents & POLLIN) != 0) accept_from(polled[i].fd, connections);
    }
  }
  for (const Connection& c : connections) ::close(c.fd);
}

void HttpServer::accept_from(int listening_fd, std::vector<Connection>& connections) {
  for (;;) {
    sockaddr_storage peer{};
    socklen_t length = sizeof peer;
    const int fd = ::accept4(listening_fd, reinterpret_cast<sockaddr*>(&peer), &length,
                             SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno == EINTR || errno == ECONNABORTED) continue;
      if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
        accept_paused_until_ = std::chrono::steady_clock::now() + std::chrono::milliseconds(kPollMs);
      }
      return;
    }
    const std::string host = host_of_peer(peer, length);
    if (const std::string share = make_room(host, connections); !share.empty()) {
      refused_.fetch_add(1, std::memory_order_relaxed);  // counted before the peer sees the close
      // Said in one try, never waited for: the refusal names the share it met.
      const std::string why = "hapticd " + name_ + ": " + share + "\n";
      const std::string reply = "HTTP/1.1 503 Service Unavailable\r\nContent-Type: text/plain; "
                                "charset=utf-8\r\nContent-Length: " + std::to_string(why.size()) +
                                "\r\nConnection: close\r\nRetry-After: 1\r\n\r\n" + why;
      (void)::send(fd, reply.data(), reply.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
      ::close(fd);
      continue;
    }
    Connection connection;
    connection.fd = fd;
    connection.host = host;
    connection.accepted_at = std::chrono::steady_clock::now();
    connection.deadline = std::chrono::steady_clock::now() + limits_.timeout;
    connections.push_back(std::move(connection));
  }
}

std::string HttpServer::make_room(const std::string& host, std::vector<Connection>& connections) {
  std::map<std::string, std::size_t> per_host;
  for (const Connection& c : connections) ++per_host[c.host];
  const std::size_t from_host = per_host[host];
  if (from_host >= limits_.max_connections_per_peer) {
    return "this host holds " + std::to_string(limits_.max_connections_per_peer) +
           " connections, the most one host may";
  }
  if (connections.size() < limits_.max_connections) return {};
  // Full: the least progress among the connections of hosts holding more than this one's, and
  // not in the middle of a reply (its reader is waiting for it).
  auto victim = connections.end();
  const auto progress = [](const Connection& c) {
    return std::tuple(c.answered, c.received.size(), c.accepted_at);
  };
  for (auto it = connections.begin(); it != connections.end(); ++it) {
    if (!it->pending.empty() || per_host[it->host] <= from_host + 1) continue;
    if (victim == connections.end() || progress(*it) < progress(*victim)) victim = it;
  }
  if (victim == connections.end()) {
    return "the endpoint holds " + std::to_string(limits_.max_connections) + " connections, its most";
  }
  evicted_.fetch_add(1, std::memory_order_relaxed);  // counted before the peer sees the close
  ::close(victim->fd);
  connections.erase(victim);
  return {};
}

bool HttpServer::receive(Connection& connection) {
  char buffer[4096];
  for (;;) {
    const ssize_t got = ::recv(connection.fd, buffer, sizeof buffer, 0);
    if (got > 0) {
      connection.received.append(buffer, static_cast<std::size_t>(got));
      if (connection.received.size() > limits_.max_request_bytes) return true;  // answer() refuses it
      continue;
    }
    if (got < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return true;
    if (got < 0 && errno == EINTR) continue;
    // Closed by the peer (or failed): a request already whole is still answered.
    std::size_t head_length = 0;
    if (head_end(connection.received, head_length) == std::string::npos) return false;
    connection.close_when_sent = true;
    return true;
  }
}

bool HttpServer::answer(Connection& connection) {
  std::size_t head_length = 0;
  const std::size_t end = head_end(connection.received, head_length);
  const auto reply = [&](const HttpResponse& response, bool head_only, bool keep_alive) {
    connection.pending = format_response(response, head_only, keep_alive);
    connection.sent = 0;
    connection.close_when_sent = connection.close_when_sent || !keep_alive;
    connection.deadline = std::chrono::steady_clock::now() + limits_.timeout;
    ++connection.answered;
    replies_.fetch_add(1, std::memory_order_relaxed);
  };
  const bool too_long = end == std::string::npos ? connection.received.size() > limits_.max_request_bytes
                                                 : head_length > limits_.max_request_bytes;
  if (too_long) {
    reply(HttpResponse::text(431, "hapticd " + name_ + ": the request head is longer than " +
                                      std::to_string(limits_.max_request_bytes) + " bytes\n"),
          false, false);
    return true;
  }
  if (end == std::string::npos) return false;
  HttpRequest request;
  const std::string error =
      parse_request_head(std::string_view(connection.received).substr(0, head_length), request);
  connection.received.erase(0, end);
  request.peer = connection.host;
  if (!error.empty()) {
    reply(HttpResponse::text(400, "hapticd " + name_ + ": " + error + "\n"), false, false);
    return true;
  }
  // No bodies are read: a request that announces one ends its connection after the reply.
  const bool body = request.header("content-length") != nullptr && *request.header("content-length") != "0";
  const bool keep_alive = request.keep_alive && !body && request.header("transfer-encoding") == nullptr;
  if (request.method != "GET" && request.method != "HEAD") {
    HttpResponse refusal =
        HttpResponse::text(405, "hapticd " + name_ + ": " + request.method +
                                    " is not served; the endpoint is read-only (GET only)\n");
    refusal.headers.emplace_back("Allow", "GET, HEAD");
    reply(refusal, false, false);
    return true;
  }
  HttpResponse response;
  try {
    response = handler_(request);
  } catch (const std::exception& e) {
    response = HttpResponse::text(500, "hapticd " + name_ + ": " + e.what() + "\n");
  }
  reply(response, request.method == "HEAD", keep_alive);
  return true;
}

bool HttpServer::flush(Connection& connection) {
  while (connection.sent < connection.pending.size()) {
    const ssize_t sent = ::send(connection.fd, connection.pending.data() + connection.sent,
                                connection.pending.size() - connection.sent, MSG_NOSIGNAL);
    if (sent > 0) {
      connection.sent += static_cast<std::size_t>(sent);
      // The limit is on a reader that stops, not on a large reply read slowly: progress renews it.
      connection.deadline = std::chrono::steady_clock::now() + limits_.timeout;
    } else if (sent < 0 && errno == EINTR) {
      continue;
    } else {
      return sent < 0 && (errno == EAGAIN || errno == EWOULDBLOCK);  // wait for POLLOUT
    }
  }
  connection.pending.clear();
  connection.sent = 0;
  if (connection.close_when_sent) return false;
  connection.deadline = std::chrono::steady_clock::now() + limits_.timeout;
  return true;
}

}  // namespace haptic::net
