#pragma once
// The metrics endpoint: GET /metrics answers with Prometheus' text format (and GET / with a
// pointer to it), over the plain HTTP of net::HttpServer on its own thread. Never touches the loop.

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>

#include "net/http_server.hpp"

namespace haptic::net {

class MetricsEndpoint {
 public:
  MetricsEndpoint() = default;

  /// Listens on "host:port" (port 0 picks one). Throws std::runtime_error naming what failed.
  void bind(const std::string& address) { http_.bind(address, "metrics_address"); }
  std::uint16_t port() const { return http_.port(); }

  /// Serves until stop(); `render` makes each scrape's body (called on this endpoint's thread).
  void start(std::function<std::string()> render);
  void stop() { http_.stop(); }

  /// Scrapes answered (200), for tests and the status line.
  std::uint64_t scrapes() const { return scrapes_.load(std::memory_order_relaxed); }

 private:
  HttpResponse handle(const HttpRequest& request);

  HttpServer http_{"metrics"};
  std::function<std::string()> render_;
  std::atomic<std::uint64_t> scrapes_{0};
};

}  // namespace haptic::net
