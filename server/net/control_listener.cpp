#include "net/control_listener.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>

#include "net/session_registry.hpp"
#include "net/tcp_listen.hpp"
#include "runtime/realtime.hpp"

namespace haptic::net {
namespace {

/// How often the accept thread looks for closed connections and for stop(). Unit: ms.
constexpr int kPollMs = 100;

std::string host_of_sockaddr(const sockaddr_storage& address, socklen_t length) {
  UdpAddress wrapped;  // the same normalisation as the data plane's (IPv4-mapped -> IPv4)
  wrapped.storage = address;
  wrapped.length = length;
  return host_of(wrapped);
}

ino_t inode_of(int fd) {
  struct stat info {};
  return ::fstat(fd, &info) == 0 && S_ISSOCK(info.st_mode) ? info.st_ino : 0;
}

}  // namespace

ControlListener::~ControlListener() {
  stop();
  for (const int fd : reserve_fds_) ::close(fd);
}

void ControlListener::top_up_reserves() {
  while (reserve_fds_.size() < kReserveFds) {
    const int fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
    if (fd < 0) return;
    reserve_fds_.push_back(fd);
  }
}

void ControlListener::bind(const std::string& address) {
  ListeningSockets sockets = listen_tcp(address, "gRPC", "grpc_address");
  listening_ = std::move(sockets.fds);
  port_ = sockets.port;
  reserve_fds_.reserve(kReserveFds);
  top_up_reserves();
}

void ControlListener::start(std::function<void(int fd)> serve) {
  serve_ = std::move(serve);
  stopping_.store(false);
  thread_ = std::thread([this] { accept_loop(); });
}

void ControlListener::stop() {
  stopping_.store(true);
  if (thread_.joinable()) thread_.join();
  for (const int fd : listening_) ::close(fd);
  listening_.clear();
}

std::string ControlListener::host_of_connection(int fd) {
  sockaddr_storage peer{};
  socklen_t length = sizeof peer;
  if (::getpeername(fd, reinterpret_cast<sockaddr*>(&peer), &length) != 0) return {};
  return host_of_sockaddr(peer, length);
}

void ControlListener::accept_loop() {
  std::vector<pollfd> fds;
  for (const int fd : listening_) fds.push_back(pollfd{fd, POLLIN, 0});
  while (!stopping_.load(std::memory_order_acquire)) {
    const int ready = ::poll(fds.data(), fds.size(), kPollMs);
    reap();
    top_up_reserves();  // a reserve lost to another thread is taken back as soon as fds free up
    if (ready <= 0) continue;
    for (const pollfd& p : fds) {
      if (p.revents & POLLIN) accept_one(p.fd);
    }
  }
}

void ControlListener::accept_one(int listening_fd) {
  // Everything queued now, so a burst is answered in one pass.
  for (;;) {
    sockaddr_storage peer{};
    socklen_t length = sizeof peer;
    const int fd = ::accept4(listening_fd, reinterpret_cast<sockaddr*>(&peer), &length,
                             SOCK_CLOEXEC | SOCK_NONBLOCK);
    if (fd < 0) {
      if (errno == EINTR || errno == ECONNABORTED) continue;
      if (errno == EMFILE || errno == ENFILE) {
        // No fd to accept with: free a reserved one, accept the connection and close it, so it
        // neither waits in the backlog nor keeps the listener readable forever; then re-reserve.
        if (!reserve_fds_.empty()) {
          ::close(reserve_fds_.back());
          reserve_fds_.pop_back();
        }
        const int dropped = ::accept4(listening_fd, nullptr, nullptr, SOCK_CLOEXEC);
        if (dropped >= 0) refuse(dropped, "the process is out of file descriptors", {});  // closes it
        top_up_reserves();
        if (dropped >= 0) continue;
        // Not even a reserve helped (another thread took the fd): back off rather than spin on
        // a listener that stays readable; connections wait in the backlog meanwhile.
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
      return;  // EAGAIN: nothing more; anything else: try again on the next poll
    }
    const std::string host = host_of_sockaddr(peer, length);
    const auto from_host = static_cast<std::uint32_t>(std::count_if(
        connections_.begin(), connections_.end(), [&](const Connection& c) { return c.host == host; }));
    if (connections_.size() >= limits_.max_connections) {
      refuse(fd, "max_connections reached", host);
      continue;
    }
    if (from_host >= limits_.max_connections_per_peer) {
      refuse(fd, "max_connections_per_peer reached", host);
      continue;
    }
    const int on = 1;  // gRPC sets this on the connections it accepts itself: no Nagle delay
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &on, sizeof on);
    // The fd number may be one gRPC closed and the kernel handed out again: this is the new one.
    std::erase_if(connections_, [fd](const Connection& c) { return c.fd == fd; });
    connections_.push_back(Connection{fd, inode_of(fd), host});
    counters_.accepted.fetch_add(1, std::memory_order_relaxed);
    counters_.open.store(static_cast<std::uint32_t>(connections_.size()), std::memory_order_relaxed);
    serve_(fd);
  }
}

void ControlListener::reap() {
  std::erase_if(connections_, [](const Connection& c) { return inode_of(c.fd) != c.inode; });
  counters_.open.store(static_cast<std::uint32_t>(connections_.size()), std::memory_order_relaxed);
}

void ControlListener::refuse(int fd, const char* why, const std::string& host) {
  if (fd >= 0) ::close(fd);
  counters_.refused.fetch_add(1, std::memory_order_relaxed);
  const std::int64_t now = runtime::monotonic_now_ns();
  if (now - last_refusal_log_ns_ > 1'000'000'000) {  // at most one line a second
    last_refusal_log_ns_ = now;
    spdlog::warn("control plane: connection{}{} refused: {} ({} refused so far, {} open)",
                 host.empty() ? "" : " from ", host, why,
                 counters_.refused.load(std::memory_order_relaxed), connections_.size());
  }
}

}  // namespace haptic::net
