#pragma once
// The metrics endpoint: a minimal HTTP/1.x server on its own thread answering `GET /metrics` with
// Prometheus' text format (and `GET /` with a pointer to it). One request per connection, served
// in turn: a scrape every few seconds needs no more. A connection that sends no complete request
// within 2 s is closed, so a stalled client cannot hold the endpoint. Never touches the loop.

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <thread>
#include <vector>

namespace haptic::net {

class MetricsEndpoint {
 public:
  MetricsEndpoint() = default;
  ~MetricsEndpoint();
  MetricsEndpoint(const MetricsEndpoint&) = delete;
  MetricsEndpoint& operator=(const MetricsEndpoint&) = delete;

  /// Listens on "host:port" (port 0 picks one). Throws std::runtime_error naming what failed.
  void bind(const std::string& address);
  std::uint16_t port() const { return port_; }

  /// Serves until stop(); `render` makes each scrape's body (called on this endpoint's thread).
  void start(std::function<std::string()> render);
  void stop();

  /// Scrapes answered (200), for tests and the status line.
  std::uint64_t scrapes() const { return scrapes_.load(std::memory_order_relaxed); }

 private:
  void serve_loop();
  void serve_one(int fd);

  std::vector<int> listening_;
  std::uint16_t port_ = 0;
  std::function<std::string()> render_;
  std::atomic<bool> stopping_{false};
  std::atomic<std::uint64_t> scrapes_{0};
  std::thread thread_;
};

}  // namespace haptic::net
