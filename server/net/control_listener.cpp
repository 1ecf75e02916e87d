#include "net/control_listener.hpp"

#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <spdlog/spdlog.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <mutex>
#include <stdexcept>

#include "net/tcp_listen.hpp"
#include "runtime/realtime.hpp"

namespace haptic::net {
namespace {

/// The longest the thread sleeps: how often deadlines and connections gRPC closed are looked at,
/// at the least. Unit: ms.
constexpr int kPollMs = 100;

/// What an epoll event is about: the low two bits of its data, the rest an id.
enum Tag : std::uint64_t { kWake = 0, kListening = 1, kNetSide = 2, kAppSide = 3 };
std::uint64_t tagged(std::uint64_t id, Tag tag) { return (id << 2) | tag; }

ino_t inode_of(int fd) {
  struct stat info {};
  return ::fstat(fd, &info) == 0 && S_ISSOCK(info.st_mode) ? info.st_ino : 0;
}

/// The descriptors handed to gRPC, with the host each came from: with TLS gRPC holds one end of
/// a socket pair, whose own peer address says nothing. Keyed by descriptor and checked against
/// the socket's inode, since gRPC reuses a number once it closes it.
struct HandedOut {
  ino_t inode = 0;
  std::string host;
};
std::mutex handed_out_mutex;
std::unordered_map<int, HandedOut>& handed_out() {
  static std::unordered_map<int, HandedOut> map;
  return map;
}

void remember_handed_out(int fd, const std::string& host) {
  std::lock_guard lock(handed_out_mutex);
  handed_out()[fd] = HandedOut{inode_of(fd), host};
}

void forget_handed_out(int fd, ino_t inode) {
  std::lock_guard lock(handed_out_mutex);
  const auto it = handed_out().find(fd);
  if (it != handed_out().end() && (inode == 0 || it->second.inode == inode)) handed_out().erase(it);
}

std::uint32_t epoll_events(bool read, bool write) {
  return (read ? EPOLLIN : 0u) | (write ? EPOLLOUT : 0u);
}

}  // namespace

ControlListener::ControlListener(const ConnectionLimits& limits,
                                 std::shared_ptr<const TlsServerContext> tls)
    : limits_(limits), tls_(std::move(tls)) {}

ControlListener::~ControlListener() {
  stop();
  for (const int fd : reserve_fds_) ::close(fd);
  if (epoll_fd_ >= 0) ::close(epoll_fd_);
  if (wake_fd_ >= 0) ::close(wake_fd_);
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
  epoll_fd_ = ::epoll_create1(EPOLL_CLOEXEC);
  wake_fd_ = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (epoll_fd_ < 0 || wake_fd_ < 0) {
    throw std::runtime_error(std::string("gRPC listener: cannot make its epoll: ") + std::strerror(errno));
  }
  epoll_event wake{EPOLLIN, {.u64 = tagged(0, kWake)}};
  ::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, wake_fd_, &wake);
  for (std::size_t i = 0; i < listening_.size(); ++i) {
    epoll_event event{EPOLLIN, {.u64 = tagged(i, kListening)}};
    ::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, listening_[i], &event);
  }
  reserve_fds_.reserve(kReserveFds);
  top_up_reserves();
}

void ControlListener::start(std::function<void(int fd)> serve) {
  serve_ = std::move(serve);
  stopping_.store(false);
  accepting_.store(true);
  thread_ = std::thread([this] { accept_loop(); });
}

void ControlListener::stop_accepting() {
  if (!accepting_.exchange(false)) return;
  if (!thread_.joinable()) {  // never started: nothing else touches the sockets
    for (const int fd : listening_) ::close(fd);
    listening_.clear();
    return;
  }
  const std::uint64_t one = 1;
  (void)::write(wake_fd_, &one, sizeof one);
  // The thread closes them on its next pass; wait for that, so no connection is accepted after.
  while (!listening_closed_.load(std::memory_order_acquire)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

void ControlListener::stop() {
  stop_accepting();
  stopping_.store(true);
  if (wake_fd_ >= 0) {
    const std::uint64_t one = 1;
    (void)::write(wake_fd_, &one, sizeof one);
  }
  if (thread_.joinable()) thread_.join();
  for (const int fd : listening_) ::close(fd);
  listening_.clear();
  while (!connections_.empty()) remove(connections_.begin()->first);
}

std::string ControlListener::host_of_connection(int fd) {
  {
    std::lock_guard lock(handed_out_mutex);
    const auto it = handed_out().find(fd);
    if (it != handed_out().end() && it->second.inode == inode_of(fd)) return it->second.host;
  }
  sockaddr_storage peer{};
  socklen_t length = sizeof peer;
  if (::getpeername(fd, reinterpret_cast<sockaddr*>(&peer), &length) != 0) return {};
  if (peer.ss_family != AF_INET && peer.ss_family != AF_INET6) return {};
  return host_of_peer(peer, length);
}

void ControlListener::accept_loop() {
  std::vector<epoll_event> events(64);
  std::int64_t last_sweep_ns = 0;
  while (!stopping_.load(std::memory_order_acquire)) {
    const int ready = ::epoll_wait(epoll_fd_, events.data(), static_cast<int>(events.size()), kPollMs);
    if (!accepting_.load(std::memory_order_acquire) && !listening_.empty()) {
      for (const int fd : listening_) ::close(fd);  // closing also takes them out of epoll
      listening_.clear();
      listening_closed_.store(true, std::memory_order_release);
    }
    for (int i = 0; i < ready; ++i) {
      const std::uint64_t data = events[i].data.u64;
      const auto tag = static_cast<Tag>(data & 3);
      const std::uint64_t id = data >> 2;
      if (tag == kWake) {
        std::uint64_t count = 0;
        (void)::read(wake_fd_, &count, sizeof count);
        continue;
      }
      if (tag == kListening) {
        if (id < listening_.size()) accept_one(listening_[id]);
        continue;
      }
      const auto it = connections_.find(id);
      if (it == connections_.end()) continue;  // removed earlier in this batch
      if (it->second.state == Connection::State::kAwaitingPreface) {
        on_awaiting_preface(id, it->second);
      } else if (it->second.state == Connection::State::kTls) {
        on_tls(id, it->second, tag == kNetSide ? events[i].events : 0u);
      }
    }
    const std::int64_t now = runtime::monotonic_now_ns();
    if (now - last_sweep_ns >= 20'000'000) {  // at most every 20 ms: O(connections) each time
      last_sweep_ns = now;
      expire_and_reap();
      top_up_reserves();  // a reserve lost to another thread is taken back as soon as fds free up
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
    const std::string host = host_of_peer(peer, length);
    if (!make_room(host)) {
      refuse(fd, connections_.size() >= limits_.max_connections ? "max_connections reached"
                                                                : "max_connections_per_peer reached",
             host);
      continue;
    }
    const int on = 1;  // gRPC sets this on the connections it accepts itself: no Nagle delay
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &on, sizeof on);
    const std::uint64_t id = next_id_++;
    Connection& connection = connections_[id];
    connection.fd = fd;
    connection.host = host;
    connection.accepted_ns = runtime::monotonic_now_ns();
    counters_.accepted.fetch_add(1, std::memory_order_relaxed);
    if (tls_) {
      ssl_st* ssl = tls_->new_connection(fd);
      if (ssl == nullptr) {
        connections_.erase(id);
        refuse(fd, "no memory for a TLS connection", host);
        continue;
      }
      connection.state = Connection::State::kTls;
      connection.pump = std::make_unique<TlsPump>(ssl, fd);  // owns fd from here
      connection.fd = -1;
      epoll_event event{EPOLLIN, {.u64 = tagged(id, kNetSide)}};
      ::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, fd, &event);
      connection.watched.net_read = true;
      update_open();
      on_tls(id, connection, 0);  // the ClientHello has usually arrived with the connection
    } else {
      // Edge-triggered: a preface that has arrived in part wakes the thread again only when more
      // comes, instead of on every pass.
      epoll_event event{EPOLLIN | EPOLLRDHUP | EPOLLET, {.u64 = tagged(id, kNetSide)}};
      ::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, fd, &event);
      update_open();
    }
  }
}

bool ControlListener::make_room(const std::string& host) {
  std::unordered_map<std::string, std::uint32_t> per_host;
  for (const auto& [id, c] : connections_) ++per_host[c.host];
  const std::uint32_t from_host = per_host.contains(host) ? per_host[host] : 0;
  if (from_host >= limits_.max_connections_per_peer) return false;
  if (connections_.size() < limits_.max_connections) return true;
  // Full: displace the oldest unserved connection of the host holding most, if it holds more
  // than this one's host would.
  const Connection* victim = nullptr;
  std::uint64_t victim_id = 0;
  for (const auto& [id, c] : connections_) {
    if (!c.unserved() || c.host == host || per_host[c.host] <= from_host + 1) continue;
    if (victim == nullptr || per_host[c.host] > per_host[victim->host] ||
        (per_host[c.host] == per_host[victim->host] && c.accepted_ns < victim->accepted_ns)) {
      victim = &c;
      victim_id = id;
    }
  }
  if (victim == nullptr) return false;
  log_limited("control plane: a connection from " + victim->host + " (" +
              std::to_string(per_host[victim->host]) + " held, no HTTP/2 preface yet) closed to make "
              "room at max_connections for one from " + host);
  counters_.evicted.fetch_add(1, std::memory_order_relaxed);  // counted before it is closed
  remove(victim_id);
  return true;
}

void ControlListener::on_awaiting_preface(std::uint64_t id, Connection& connection) {
  char bytes[kHttp2PrefaceBytes];
  const ssize_t n = ::recv(connection.fd, bytes, sizeof bytes, MSG_PEEK);
  if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) return;
  if (n <= 0) {  // closed before saying anything, or failed
    remove(id);
    return;
  }
  switch (check_http2_preface(std::string_view(bytes, static_cast<std::size_t>(n)))) {
    case PrefaceCheck::kSoFar:
      return;  // the rest wakes the thread again (edge-triggered)
    case PrefaceCheck::kNotHttp2:
      log_limited("control plane: a connection from " + connection.host +
                  " closed: not an HTTP/2 client" +
                  (bytes[0] == 0x16 ? " (it speaks TLS; this server is plaintext)" : ""));
      remove(id);
      return;
    case PrefaceCheck::kComplete:
      break;
  }
  // The preface stays in the socket (only peeked at): gRPC reads it as if it had accepted.
  ::epoll_ctl(epoll_fd_, EPOLL_CTL_DEL, connection.fd, nullptr);
  connection.state = Connection::State::kServed;
  connection.inode = inode_of(connection.fd);
  hand_over(connection, connection.fd);
}

void ControlListener::on_tls(std::uint64_t id, Connection& connection, std::uint32_t net_events) {
  TlsPump& pump = *connection.pump;
  TlsPump::Stage stage = pump.advance();
  if (stage == TlsPump::Stage::kReadyToServe) {
    int pair[2];
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, pair) != 0) {
      refuse(-1, "the process is out of file descriptors", connection.host);
      remove(id);
      return;
    }
    pump.attach_app(pair[0]);
    connection.grpc_fd = pair[1];
    hand_over(connection, pair[1]);
    stage = pump.advance();  // the preface and what came with it, on to gRPC
  }
  if (stage == TlsPump::Stage::kClosed) {
    if (!pump.handshake_done()) {
      counters_.tls_failed.fetch_add(1, std::memory_order_relaxed);
      log_limited("control plane: TLS handshake from " + connection.host + " failed: " + pump.why());
    }
    remove(id);
    return;
  }
  // A socket that has failed or hung up while the pump waits for nothing on it would wake the
  // thread on every pass: nothing more can come from it.
  if ((net_events & (EPOLLERR | EPOLLHUP)) != 0 && !pump.interest().net_read) {
    remove(id);
    return;
  }
  watch_tls(id, connection);
}

void ControlListener::hand_over(Connection& connection, int grpc_fd) {
  remember_handed_out(grpc_fd, connection.host);
  serve_(grpc_fd);
}

void ControlListener::watch_tls(std::uint64_t id, Connection& connection) {
  const TlsPump& pump = *connection.pump;
  const TlsPump::Interest want = pump.interest();
  if (want.net_read != connection.watched.net_read || want.net_write != connection.watched.net_write) {
    epoll_event event{epoll_events(want.net_read, want.net_write), {.u64 = tagged(id, kNetSide)}};
    ::epoll_ctl(epoll_fd_, EPOLL_CTL_MOD, pump.net_fd(), &event);
  }
  if (pump.app_fd() >= 0 &&
      (!connection.app_watched || want.app_read != connection.watched.app_read ||
       want.app_write != connection.watched.app_write)) {
    epoll_event event{epoll_events(want.app_read, want.app_write), {.u64 = tagged(id, kAppSide)}};
    ::epoll_ctl(epoll_fd_, connection.app_watched ? EPOLL_CTL_MOD : EPOLL_CTL_ADD, pump.app_fd(), &event);
    connection.app_watched = true;
  }
  connection.watched = want;
}

void ControlListener::remove(std::uint64_t id) {
  auto node = connections_.extract(id);
  if (node.empty()) return;
  // The count first, the sockets after: whoever sees a connection closed finds it counted.
  update_open();
  Connection& connection = node.mapped();
  switch (connection.state) {
    case Connection::State::kAwaitingPreface:
      ::close(connection.fd);  // closing also takes it out of epoll
      break;
    case Connection::State::kTls:
      if (connection.grpc_fd >= 0) forget_handed_out(connection.grpc_fd, 0);
      break;  // the pump closes its sockets when the node goes, below
    case Connection::State::kServed:
      forget_handed_out(connection.fd, connection.inode);
      break;  // gRPC's to close
  }
}

void ControlListener::expire_and_reap() {
  const std::int64_t now = runtime::monotonic_now_ns();
  const std::int64_t timeout_ns =
      std::chrono::duration_cast<std::chrono::nanoseconds>(limits_.handshake_timeout).count();
  std::vector<std::uint64_t> ended;
  std::uint64_t expired = 0;
  for (const auto& [id, c] : connections_) {
    if (c.state == Connection::State::kServed) {
      if (inode_of(c.fd) != c.inode) ended.push_back(id);  // gRPC has closed it
    } else if (c.unserved() && now - c.accepted_ns > timeout_ns) {
      ended.push_back(id);
      ++expired;
    }
  }
  // Counted before they are closed: whoever sees one closed finds it counted.
  counters_.timed_out.fetch_add(expired, std::memory_order_relaxed);
  for (const std::uint64_t id : ended) remove(id);
  if (expired > 0) {
    log_limited("control plane: " + std::to_string(expired) + " connection(s) closed: no " +
                (tls_ ? "TLS handshake and " : "") + "HTTP/2 preface within handshake_timeout_ms (" +
                std::to_string(limits_.handshake_timeout.count()) + ")");
  }
}

void ControlListener::update_open() {
  counters_.open.store(static_cast<std::uint32_t>(connections_.size()), std::memory_order_relaxed);
}

void ControlListener::refuse(int fd, const char* why, const std::string& host) {
  counters_.refused.fetch_add(1, std::memory_order_relaxed);  // counted before the peer sees the close
  if (fd >= 0) ::close(fd);
  log_limited(std::string("control plane: connection") + (host.empty() ? "" : " from " + host) +
              " refused: " + why + " (" +
              std::to_string(counters_.refused.load(std::memory_order_relaxed)) + " refused so far, " +
              std::to_string(connections_.size()) + " open)");
}

void ControlListener::log_limited(const std::string& line) {
  const std::int64_t now = runtime::monotonic_now_ns();
  if (now - last_log_ns_ < 1'000'000'000) {  // at most one line a second
    ++lines_held_back_;
    return;
  }
  last_log_ns_ = now;
  if (lines_held_back_ > 0) {
    spdlog::warn("{} ({} similar lines held back)", line, lines_held_back_);
    lines_held_back_ = 0;
  } else {
    spdlog::warn("{}", line);
  }
}

}  // namespace haptic::net
