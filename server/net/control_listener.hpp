#pragma once
// The control plane's TCP listener. hapticd accepts gRPC connections itself and hands each to the
// gRPC server (grpc::AddInsecureChannelFromFd), because gRPC 1.51's own listener stops for good
// after one accept() fails with EMFILE (grpc/grpc#20418): a flood of idle connections left the
// control plane deaf until a restart while the loop carried on. Here:
//   - connections are capped per peer host and in all, below the process's fd limit; one over a
//     cap is accepted and closed at once (counted), so the backlog never fills with them;
//   - if accept() still runs out of fds, a reserved descriptor is released to accept and close
//     the connection, and the listener carries on: it recovers as soon as fds are free again;
//   - the port is bound exclusively (no SO_REUSEPORT): a second server on it fails at start.
// One thread; off the loop.

#include <sys/types.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <thread>
#include <vector>

namespace haptic::net {

struct ConnectionLimits {
  std::uint32_t max_connections = 1024;          // open at once, every peer together
  std::uint32_t max_connections_per_peer = 64;   // open at once from one host
};

struct ConnectionCounters {
  std::atomic<std::uint64_t> accepted{0};
  std::atomic<std::uint64_t> refused{0};       // over a cap, or no fd to hold them
  std::atomic<std::uint32_t> open{0};          // handed to gRPC and not yet closed by it
};

class ControlListener {
 public:
  explicit ControlListener(const ConnectionLimits& limits) : limits_(limits) {}
  ~ControlListener();
  ControlListener(const ControlListener&) = delete;
  ControlListener& operator=(const ControlListener&) = delete;

  /// Binds and listens on every address `address` ("host:port", "[v6]:port") resolves to; port 0
  /// picks one free port, the same for all. Throws std::runtime_error naming the address and why.
  void bind(const std::string& address);
  std::uint16_t port() const { return port_; }

  /// Starts accepting: each connection within the caps goes to `serve` (which takes ownership of
  /// the descriptor: gRPC closes it when the connection ends).
  void start(std::function<void(int fd)> serve);
  /// Stops accepting and closes the listening sockets (connections already served stay gRPC's).
  void stop();

  /// The host a connection handed out as descriptor `fd` comes from (peer_host()'s form); "" if
  /// it is not one of ours or has gone.
  static std::string host_of_connection(int fd);

  const ConnectionCounters& counters() const { return counters_; }

 private:
  struct Connection {
    int fd = -1;
    ino_t inode = 0;  // the socket's identity: the fd number alone may be reused once gRPC closes it
    std::string host;
  };

  void accept_loop();
  void accept_one(int listening_fd);
  /// Forgets the connections gRPC has closed since the last look.
  void reap();
  void refuse(int fd, const char* why, const std::string& host);

  ConnectionLimits limits_;
  std::vector<int> listening_;
  std::uint16_t port_ = 0;
  /// Descriptors held so that accept() can be made to succeed when the process runs out: one is
  /// freed to accept (and refuse) a connection, and taken back. Several, and topped up on every
  /// pass, because another thread (gRPC's) may take a freed number first: with a single reserve
  /// that race once left the listener unable to refuse anything until a connection closed.
  std::vector<int> reserve_fds_;
  static constexpr std::size_t kReserveFds = 4;
  /// Opens reserves up to kReserveFds (as many as the process can have).
  void top_up_reserves();
  std::function<void(int)> serve_;
  std::vector<Connection> connections_;  // accept thread only
  std::atomic<bool> stopping_{false};
  std::thread thread_;
  ConnectionCounters counters_;
  std::int64_t last_refusal_log_ns_ = 0;  // accept thread only
};

}  // namespace haptic::net
