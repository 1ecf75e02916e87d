#include "net/metrics_endpoint.hpp"

#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <string_view>

#include "net/tcp_listen.hpp"

namespace haptic::net {
namespace {

constexpr int kPollMs = 100;              // how often the thread looks for stop()
constexpr auto kRequestTimeout = std::chrono::seconds(2);
constexpr std::size_t kMaxRequestBytes = 8192;

void send_all(int fd, std::string_view bytes) {
  const auto give_up = std::chrono::steady_clock::now() + kRequestTimeout;
  while (!bytes.empty() && std::chrono::steady_clock::now() < give_up) {
    const ssize_t sent = ::send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL);
    if (sent > 0) {
      bytes.remove_prefix(static_cast<std::size_t>(sent));
    } else if (sent < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) {
      pollfd out{fd, POLLOUT, 0};
      ::poll(&out, 1, kPollMs);
    } else {
      return;
    }
  }
}

std::string response(const char* status, const char* content_type, const std::string& body) {
  return std::string("HTTP/1.1 ") + status + "\r\nContent-Type: " + content_type +
         "\r\nContent-Length: " + std::to_string(body.size()) + "\r\nConnection: close\r\n\r\n" +
         body;
}

}  // namespace

MetricsEndpoint::~MetricsEndpoint() { stop(); }

void MetricsEndpoint::bind(const std::string& address) {
  ListeningSockets sockets = listen_tcp(address, "metrics", "metrics_address");
  listening_ = std::move(sockets.fds);
  port_ = sockets.port;
}

void MetricsEndpoint::start(std::function<std::string()> render) {
  render_ = std::move(render);
  stopping_.store(false);
  thread_ = std::thread([this] { serve_loop(); });
}

void MetricsEndpoint::stop() {
  stopping_.store(true);
  if (thread_.joinable()) thread_.join();
  for (const int fd : listening_) ::close(fd);
  listening_.clear();
}

void MetricsEndpoint::serve_loop() {
  std::vector<pollfd> polled;
  for (const int fd : listening_) polled.push_back({fd, POLLIN, 0});
  while (!stopping_.load()) {
    if (::poll(polled.data(), polled.size(), kPollMs) <= 0) continue;
    for (const pollfd& p : polled) {
      if ((p.revents & POLLIN) == 0) continue;
      const int connection = ::accept4(p.fd, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
      if (connection < 0) continue;
      serve_one(connection);
      ::close(connection);
    }
  }
}

void MetricsEndpoint::serve_one(int fd) {
  // Read the request head (to the blank line), within the time and size limits.
  std::string request;
  const auto give_up = std::chrono::steady_clock::now() + kRequestTimeout;
  while (request.find("\r\n\r\n") == std::string::npos && request.find("\n\n") == std::string::npos) {
    if (request.size() > kMaxRequestBytes || std::chrono::steady_clock::now() >= give_up ||
        stopping_.load()) {
      return;
    }
    pollfd in{fd, POLLIN, 0};
    if (::poll(&in, 1, kPollMs) <= 0) continue;
    char buffer[1024];
    const ssize_t got = ::recv(fd, buffer, sizeof buffer, 0);
    if (got <= 0) {
      if (got < 0 && (errno == EAGAIN || errno == EINTR)) continue;
      return;
    }
    request.append(buffer, static_cast<std::size_t>(got));
  }
  const std::string_view line(request.data(), request.find_first_of("\r\n"));
  const auto first_space = line.find(' ');
  const auto second_space = line.find(' ', first_space + 1);
  const std::string_view method = line.substr(0, first_space);
  const std::string_view target = first_space == std::string_view::npos
                                      ? std::string_view()
                                      : line.substr(first_space + 1, second_space - first_space - 1);
  const std::string_view path = target.substr(0, target.find('?'));
  if (method != "GET" && method != "HEAD") {
    send_all(fd, response("405 Method Not Allowed", "text/plain; charset=utf-8",
                          "hapticd metrics: only GET\n"));
    return;
  }
  if (path == "/metrics") {
    const std::string body = render_();
    std::string reply = response("200 OK", "text/plain; version=0.0.4; charset=utf-8", body);
    if (method == "HEAD") reply.resize(reply.size() - body.size());
    send_all(fd, reply);
    scrapes_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  if (path == "/") {
    send_all(fd, response("200 OK", "text/plain; charset=utf-8",
                          "hapticd: metrics in Prometheus' text format at /metrics\n"));
    return;
  }
  send_all(fd, response("404 Not Found", "text/plain; charset=utf-8",
                        "hapticd metrics: no " + std::string(path) + "; see /metrics\n"));
}

}  // namespace haptic::net
