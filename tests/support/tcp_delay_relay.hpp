#pragma once
// The control plane's half of the simulated LAN (see udp_impairment_relay.hpp): a TCP relay on a
// loopback port that forwards each connection to the server after a fixed one-way delay, in order,
// and that can be partitioned (a pulled cable: bytes wait, connections stay open, as TCP's
// retransmissions would keep them across a short outage). Loss on TCP is retransmission delay,
// which a fixed delay stands for here.

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace haptic::test {

class TcpDelayRelay {
 public:
  TcpDelayRelay(std::uint16_t server_port, std::chrono::microseconds one_way_delay)
      : delay_us_(one_way_delay.count()) {
    server_.sin_family = AF_INET;
    server_.sin_port = htons(server_port);
    server_.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    listener_ = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    sockaddr_in any{};
    any.sin_family = AF_INET;
    any.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (listener_ < 0 || ::bind(listener_, reinterpret_cast<sockaddr*>(&any), sizeof(any)) != 0 ||
        ::listen(listener_, 64) != 0) {
      throw std::runtime_error("tcp relay: cannot listen");
    }
    socklen_t length = sizeof(any);
    ::getsockname(listener_, reinterpret_cast<sockaddr*>(&any), &length);
    port_ = ntohs(any.sin_port);
    thread_ = std::thread([this] { run(); });
  }
  ~TcpDelayRelay() {
    stopping_ = true;
    if (thread_.joinable()) thread_.join();
    for (const auto& pair : pairs_) {
      ::close(pair->client);
      ::close(pair->server);
    }
    ::close(listener_);
  }
  TcpDelayRelay(const TcpDelayRelay&) = delete;
  TcpDelayRelay& operator=(const TcpDelayRelay&) = delete;

  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
  /// The one-way delay of bytes read from now on.
  void set_delay(std::chrono::microseconds one_way_delay) { delay_us_ = one_way_delay.count(); }
  /// While set, bytes either way wait (connections stay open); cleared, they flow again.
  void set_partitioned(bool partitioned) { partitioned_ = partitioned; }

 private:
  struct Chunk {
    std::chrono::steady_clock::time_point due;
    std::vector<std::uint8_t> bytes;
    std::size_t sent = 0;
  };
  struct Pair {
    int client = -1;
    int server = -1;
    std::deque<Chunk> to_server;
    std::deque<Chunk> to_client;
    bool closed = false;
  };

  // Reads what `from` has into `queue`; false when it closed or failed.
  bool read_into(int from, std::deque<Chunk>& queue) {
    std::uint8_t buffer[16384];
    for (;;) {
      const ssize_t size = ::recv(from, buffer, sizeof(buffer), 0);
      if (size > 0) {
        queue.push_back({std::chrono::steady_clock::now() + std::chrono::microseconds(delay_us_.load()),
                          {buffer, buffer + size}, 0});
        continue;
      }
      if (size == 0) return false;
      return errno == EAGAIN || errno == EWOULDBLOCK;
    }
  }
  // Writes the due part of `queue` to `to`; false when it failed.
  bool write_due(int to, std::deque<Chunk>& queue) {
    const auto now = std::chrono::steady_clock::now();
    while (!queue.empty() && queue.front().due <= now && !partitioned_) {
      Chunk& chunk = queue.front();
      const ssize_t size = ::send(to, chunk.bytes.data() + chunk.sent, chunk.bytes.size() - chunk.sent,
                                  MSG_NOSIGNAL | MSG_DONTWAIT);
      if (size < 0) return errno == EAGAIN || errno == EWOULDBLOCK;
      chunk.sent += static_cast<std::size_t>(size);
      if (chunk.sent < chunk.bytes.size()) return true;
      queue.pop_front();
    }
    return true;
  }

  void accept_new() {
    for (;;) {
      const int client = ::accept4(listener_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
      if (client < 0) return;
      const int server = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
      // A blocking connect on loopback: at once, or refused (no server: the client sees a close).
      if (server < 0 || ::connect(server, reinterpret_cast<const sockaddr*>(&server_), sizeof(server_)) != 0) {
        if (server >= 0) ::close(server);
        ::close(client);
        continue;
      }
      ::fcntl(server, F_SETFL, ::fcntl(server, F_GETFL) | O_NONBLOCK);
      const int one = 1;
      ::setsockopt(client, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
      ::setsockopt(server, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
      auto pair = std::make_unique<Pair>();
      pair->client = client;
      pair->server = server;
      pairs_.push_back(std::move(pair));
    }
  }

  void run() {
    while (!stopping_) {
      std::vector<pollfd> fds{{listener_, POLLIN, 0}};
      if (!partitioned_) {
        for (const auto& pair : pairs_) {
          fds.push_back({pair->client, POLLIN, 0});
          fds.push_back({pair->server, POLLIN, 0});
        }
      }
      ::poll(fds.data(), fds.size(), 1);
      accept_new();
      if (partitioned_) continue;  // nothing read or written: bytes wait in the kernel's buffers
      for (auto& pair : pairs_) {
        const bool open = read_into(pair->client, pair->to_server) && read_into(pair->server, pair->to_client) &&
                          write_due(pair->server, pair->to_server) && write_due(pair->client, pair->to_client);
        if (!open) pair->closed = true;
      }
      // A connection one side closed ends at the other too (after what was queued, roughly).
      for (auto it = pairs_.begin(); it != pairs_.end();) {
        if ((*it)->closed) {
          ::close((*it)->client);
          ::close((*it)->server);
          it = pairs_.erase(it);
        } else {
          ++it;
        }
      }
    }
  }

  sockaddr_in server_{};
  std::atomic<std::int64_t> delay_us_;
  int listener_ = -1;
  std::uint16_t port_ = 0;
  std::vector<std::unique_ptr<Pair>> pairs_;  // relay thread only
  std::atomic<bool> partitioned_{false};
  std::atomic<bool> stopping_{false};
  std::thread thread_;
};

}  // namespace haptic::test
