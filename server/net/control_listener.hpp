#pragma once
// The control plane's TCP listener, in plaintext and with TLS alike. hapticd accepts gRPC
// connections itself and hands each to the gRPC server (grpc::AddInsecureChannelFromFd), because
// gRPC 1.51's own listener stops for good after one accept() fails with EMFILE (grpc/grpc#20418):
// a flood of idle connections left the control plane deaf until a restart while the loop carried
// on. gRPC takes only plaintext from a descriptor, so with TLS this listener also terminates it
// (OpenSSL, net::TlsServerContext) and gives gRPC the other end of a socket pair, copying between
// the two (net::TlsPump). Here:
//   - connections are capped per peer host and in all, below the process's fd limit; one over a
//     cap is accepted and closed at once (counted), so the backlog never fills with them;
//   - at the cap in all, a newcomer from a host holding fewer connections displaces the oldest
//     connection that has not yet sent its HTTP/2 preface of the host holding most: one host's
//     idle flood cannot lock the others out;
//   - a connection is handed to gRPC only once it has completed its TLS handshake (with TLS) and
//     sent the HTTP/2 client preface; one that does neither within handshake_timeout is closed;
//   - if accept() still runs out of fds, a reserved descriptor is released to accept and close
//     the connection, and the listener carries on: it recovers as soon as fds are free again;
//   - the port is bound exclusively (no SO_REUSEPORT): a second server on it fails at start.
// One thread (epoll); off the loop.

#include <sys/types.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "net/tls_pump.hpp"
#include "net/tls_server_context.hpp"

namespace haptic::net {

struct ConnectionLimits {
  std::uint32_t max_connections = 1024;          // open at once, every peer together
  std::uint32_t max_connections_per_peer = 64;   // open at once from one host
  /// To complete the TLS handshake and send the HTTP/2 preface, from accept().
  std::chrono::milliseconds handshake_timeout{5000};
};

struct ConnectionCounters {
  std::atomic<std::uint64_t> accepted{0};
  std::atomic<std::uint64_t> refused{0};       // over a cap, or no fd to hold them
  std::atomic<std::uint32_t> open{0};          // held now: awaiting their preface, or served
  std::atomic<std::uint64_t> timed_out{0};     // no handshake or preface within the timeout
  std::atomic<std::uint64_t> evicted{0};       // displaced at the cap by another host's newcomer
  std::atomic<std::uint64_t> tls_failed{0};    // TLS handshakes that failed
};

class ControlListener {
 public:
  /// `tls`: terminate TLS with it; nullptr: plaintext.
  explicit ControlListener(const ConnectionLimits& limits,
                           std::shared_ptr<const TlsServerContext> tls = nullptr);
  ~ControlListener();
  ControlListener(const ControlListener&) = delete;
  ControlListener& operator=(const ControlListener&) = delete;

  /// Binds and listens on every address `address` ("host:port", "[v6]:port") resolves to; port 0
  /// picks one free port, the same for all. Throws std::runtime_error naming the address and why.
  void bind(const std::string& address);
  std::uint16_t port() const { return port_; }

  /// Starts accepting: each connection within the caps that has sent its preface goes to `serve`
  /// (which takes ownership of the descriptor: gRPC closes it when the connection ends).
  void start(std::function<void(int fd)> serve);
  /// Stops accepting and closes the listening sockets; connections already served go on (with
  /// TLS this listener still carries them) until stop(). Idempotent.
  void stop_accepting();
  /// Stops everything: with TLS, the connections it carries end here. Idempotent.
  void stop();

  /// The host a connection handed out as descriptor `fd` comes from (peer_host()'s form); "" if
  /// it is not one of ours or has gone.
  static std::string host_of_connection(int fd);

  const ConnectionCounters& counters() const { return counters_; }

 private:
  struct Connection {
    enum class State {
      kAwaitingPreface,  // plaintext, not yet handed over (this listener holds the socket)
      kTls,              // TLS: the pump holds the socket (and, once served, the pair's end)
      kServed,           // plaintext, gRPC's: watched only to notice when gRPC closes it
    };
    State state = State::kAwaitingPreface;
    int fd = -1;       // the TCP socket (kAwaitingPreface); gRPC's descriptor (kServed)
    ino_t inode = 0;   // kServed: the socket's identity (the fd number may be reused once closed)
    int grpc_fd = -1;  // kTls, once served: the pair's end gRPC holds
    std::string host;
    std::int64_t accepted_ns = 0;
    std::unique_ptr<TlsPump> pump;  // kTls
    TlsPump::Interest watched;      // kTls: what epoll waits for now
    bool app_watched = false;       // kTls: the pair's end is in epoll
    /// Not yet handed to gRPC: still under the handshake deadline, and may be displaced.
    bool unserved() const {
      return state == State::kAwaitingPreface ||
             (state == State::kTls && pump->stage() != TlsPump::Stage::kOpen);
    }
  };

  void accept_loop();
  void accept_one(int listening_fd);
  /// Whether `host` may have one more connection, displacing another host's if need be.
  bool make_room(const std::string& host);
  void on_awaiting_preface(std::uint64_t id, Connection& connection);
  void on_tls(std::uint64_t id, Connection& connection, std::uint32_t net_events);
  void hand_over(Connection& connection, int grpc_fd);
  void watch_tls(std::uint64_t id, Connection& connection);
  void remove(std::uint64_t id);
  /// Closes the unserved connections past their deadline; forgets those gRPC has closed.
  void expire_and_reap();
  void refuse(int fd, const char* why, const std::string& host);
  void log_limited(const std::string& line);
  void update_open();
  /// Opens reserves up to kReserveFds (as many as the process can have).
  void top_up_reserves();

  ConnectionLimits limits_;
  std::shared_ptr<const TlsServerContext> tls_;
  std::vector<int> listening_;
  std::uint16_t port_ = 0;
  int epoll_fd_ = -1;
  int wake_fd_ = -1;  // an eventfd: stop_accepting() and stop() wake the thread through it
  /// Descriptors held so that accept() can be made to succeed when the process runs out: one is
  /// freed to accept (and refuse) a connection, and taken back. Several, and topped up on every
  /// pass, because another thread (gRPC's) may take a freed number first: with a single reserve
  /// that race once left the listener unable to refuse anything until a connection closed.
  std::vector<int> reserve_fds_;
  static constexpr std::size_t kReserveFds = 4;
  std::function<void(int)> serve_;
  std::unordered_map<std::uint64_t, Connection> connections_;  // by id; accept thread only
  std::uint64_t next_id_ = 1;
  std::atomic<bool> accepting_{true};
  std::atomic<bool> listening_closed_{false};  // the thread has closed the listening sockets
  std::atomic<bool> stopping_{false};
  std::thread thread_;
  ConnectionCounters counters_;
  std::int64_t last_log_ns_ = 0;      // accept thread only
  std::uint64_t lines_held_back_ = 0; // log lines not written for the rate limit
};

}  // namespace haptic::net
