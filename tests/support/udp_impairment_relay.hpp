#pragma once
// A simulated LAN for the data plane, in user space: a UDP relay between clients and a server that
// delays, jitters, drops, duplicates and reorders datagrams the way `tc netem` does, with its own
// seeded random numbers so a run's decisions can be reproduced. Clients send to the relay's port
// (haptic::ClientConfig::udp_address); each client gets a socket of its own towards the server, so
// the server sees one address per client, as across a real network, and answers it; the relay
// hands what comes back to that client.
//
// Used where the kernel's netem qdisc is missing (tests/integration/lan_test.cpp); it impairs UDP
// only (the control plane's TCP goes direct).

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <map>
#include <mutex>
#include <queue>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace haptic::test {

/// What happens to the datagrams going one way. Like netem: each datagram is lost with
/// probability `loss`; a kept one is delayed by `delay` plus a uniform draw in ±`jitter` (never
/// below zero), except that with probability `reorder` it goes at once, overtaking those still
/// held; with probability `duplicate` a second copy follows, delayed on its own.
struct Impairment {
  std::chrono::microseconds delay{0};
  std::chrono::microseconds jitter{0};
  double loss = 0.0;       ///< 0 ... 1
  double duplicate = 0.0;  ///< 0 ... 1
  double reorder = 0.0;    ///< 0 ... 1
};

/// What one direction saw. `states_*` count only State and StateOriented datagrams (header type
/// 1 or 5), which is what a client's ReceiveCounters can be compared with.
struct RelayCounters {
  std::uint64_t received = 0;
  std::uint64_t dropped = 0;
  std::uint64_t duplicated = 0;
  std::uint64_t sent_early = 0;  ///< reordered: sent at once past the delay
  std::uint64_t delivered = 0;
  std::uint64_t states_received = 0;
  std::uint64_t states_dropped = 0;
  std::uint64_t states_duplicated = 0;
};

class UdpImpairmentRelay {
 public:
  /// Relays to 127.0.0.1:`server_port`; listens on an ephemeral loopback port (port()).
  UdpImpairmentRelay(std::uint16_t server_port, Impairment to_server, Impairment to_client,
                     std::uint64_t seed = 1)
      : to_server_(to_server), to_client_(to_client), random_to_server_(seed),
        random_to_client_(seed ^ 0x9e3779b97f4a7c15ull) {
    server_.sin_family = AF_INET;
    server_.sin_port = htons(server_port);
    server_.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    front_ = open_socket();
    sockaddr_in bound{};
    socklen_t length = sizeof(bound);
    ::getsockname(front_, reinterpret_cast<sockaddr*>(&bound), &length);
    port_ = ntohs(bound.sin_port);
    thread_ = std::thread([this] { run(); });
  }

  ~UdpImpairmentRelay() {
    stopping_ = true;
    if (thread_.joinable()) thread_.join();
    ::close(front_);
    for (const Peer& peer : peers_) ::close(peer.back);
  }
  UdpImpairmentRelay(const UdpImpairmentRelay&) = delete;
  UdpImpairmentRelay& operator=(const UdpImpairmentRelay&) = delete;

  std::uint16_t port() const { return port_; }
  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }

  /// Changes the impairments from the next datagram on (held ones keep their times).
  void set(Impairment to_server, Impairment to_client) {
    std::lock_guard lock(mutex_);
    to_server_ = to_server;
    to_client_ = to_client;
  }
  /// A pulled cable: while set, every datagram either way is dropped (and counted).
  void set_partitioned(bool partitioned) { partitioned_ = partitioned; }

  RelayCounters to_server_counters() const {
    std::lock_guard lock(mutex_);
    return counters_[kToServer];
  }
  RelayCounters to_client_counters() const {
    std::lock_guard lock(mutex_);
    return counters_[kToClient];
  }

 private:
  enum Direction { kToServer = 0, kToClient = 1 };
  struct Peer {
    sockaddr_in client{};  // where the client sends from
    int back = -1;         // our socket towards the server for it
  };
  struct Held {
    std::chrono::steady_clock::time_point due;
    std::uint64_t order;  // ties go in arrival order
    int socket;
    sockaddr_in to;
    std::vector<std::uint8_t> bytes;
    bool operator>(const Held& other) const {
      return due != other.due ? due > other.due : order > other.order;
    }
  };

  static int open_socket() {
    const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd < 0) throw std::runtime_error("relay: socket failed");
    const int buffer = 1 << 20;
    ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &buffer, sizeof(buffer));
    sockaddr_in any{};
    any.sin_family = AF_INET;
    any.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::bind(fd, reinterpret_cast<sockaddr*>(&any), sizeof(any)) != 0) {
      ::close(fd);
      throw std::runtime_error("relay: bind failed");
    }
    return fd;
  }

  static bool is_state(const std::vector<std::uint8_t>& bytes) {
    if (bytes.size() < 8) return false;
    const unsigned type = bytes[6] | (bytes[7] << 8);  // wire header: u16 type at offset 6
    return type == 1 || type == 5;
  }

  // The peer for a client address, made on its first datagram.
  Peer& peer_for(const sockaddr_in& client) {
    for (Peer& peer : peers_) {
      if (peer.client.sin_port == client.sin_port && peer.client.sin_addr.s_addr == client.sin_addr.s_addr) {
        return peer;
      }
    }
    Peer peer;
    peer.client = client;
    peer.back = open_socket();
    peers_.push_back(peer);
    return peers_.back();
  }

  // Decides the fate of one datagram and queues what is to be sent.
  void admit(Direction direction, std::vector<std::uint8_t> bytes, int socket, const sockaddr_in& to) {
    const auto now = std::chrono::steady_clock::now();
    std::lock_guard lock(mutex_);
    const Impairment& impairment = direction == kToServer ? to_server_ : to_client_;
    std::mt19937_64& random = direction == kToServer ? random_to_server_ : random_to_client_;
    RelayCounters& counters = counters_[direction];
    const bool state = is_state(bytes);
    ++counters.received;
    if (state) ++counters.states_received;
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    // Every draw is made for every datagram, so one setting does not shift another's choices.
    const double lose = unit(random);
    const double twice = unit(random);
    const double early = unit(random);
    const double jitter_first = unit(random);
    const double jitter_copy = unit(random);
    if (partitioned_ || lose < impairment.loss) {
      ++counters.dropped;
      if (state) ++counters.states_dropped;
      return;
    }
    const auto delay_for = [&](double draw) {
      const auto jitter = std::chrono::duration_cast<std::chrono::microseconds>(
          impairment.jitter * (2.0 * draw - 1.0));
      return std::max(std::chrono::microseconds(0), impairment.delay + jitter);
    };
    const bool at_once = early < impairment.reorder;
    if (at_once) ++counters.sent_early;
    const int copies = twice < impairment.duplicate ? 2 : 1;
    if (copies == 2) {
      ++counters.duplicated;
      if (state) ++counters.states_duplicated;
    }
    for (int copy = 0; copy < copies; ++copy) {
      const auto delay = (copy == 0 && at_once) ? std::chrono::microseconds(0)
                                                : delay_for(copy == 0 ? jitter_first : jitter_copy);
      held_.push(Held{now + delay, next_order_++, socket, to, bytes});
    }
  }

  void deliver_due() {
    const auto now = std::chrono::steady_clock::now();
    std::lock_guard lock(mutex_);
    while (!held_.empty() && held_.top().due <= now) {
      const Held& next = held_.top();
      ::sendto(next.socket, next.bytes.data(), next.bytes.size(), MSG_DONTWAIT,
               reinterpret_cast<const sockaddr*>(&next.to), sizeof(next.to));
      ++counters_[next.socket == front_ ? kToClient : kToServer].delivered;
      held_.pop();
    }
  }

  int wait_ms() {
    std::lock_guard lock(mutex_);
    if (held_.empty()) return 5;
    const auto until = held_.top().due - std::chrono::steady_clock::now();
    const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(until).count();
    return static_cast<int>(std::clamp<long long>(ms, 0, 5));
  }

  void run() {
    std::vector<std::uint8_t> buffer(2048);
    while (!stopping_) {
      std::vector<pollfd> fds{{front_, POLLIN, 0}};
      for (const Peer& peer : peers_) fds.push_back({peer.back, POLLIN, 0});
      ::poll(fds.data(), fds.size(), wait_ms());
      // From clients, towards the server.
      for (;;) {
        sockaddr_in from{};
        socklen_t length = sizeof(from);
        const ssize_t size = ::recvfrom(front_, buffer.data(), buffer.size(), 0,
                                        reinterpret_cast<sockaddr*>(&from), &length);
        if (size < 0) break;
        const Peer& peer = peer_for(from);
        admit(kToServer, {buffer.begin(), buffer.begin() + size}, peer.back, server_);
      }
      // From the server, back to each client.
      for (const Peer& peer : peers_) {
        for (;;) {
          const ssize_t size = ::recv(peer.back, buffer.data(), buffer.size(), 0);
          if (size < 0) break;
          admit(kToClient, {buffer.begin(), buffer.begin() + size}, front_, peer.client);
        }
      }
      deliver_due();
    }
  }

  sockaddr_in server_{};
  int front_ = -1;
  std::uint16_t port_ = 0;
  std::vector<Peer> peers_;  // relay thread only (after construction)

  mutable std::mutex mutex_;
  Impairment to_server_;                  // guarded by mutex_
  Impairment to_client_;                  // guarded by mutex_
  std::mt19937_64 random_to_server_;      // guarded by mutex_
  std::mt19937_64 random_to_client_;      // guarded by mutex_
  RelayCounters counters_[2];             // guarded by mutex_
  std::priority_queue<Held, std::vector<Held>, std::greater<Held>> held_;  // guarded by mutex_
  std::uint64_t next_order_ = 0;          // guarded by mutex_

  std::atomic<bool> partitioned_{false};
  std::atomic<bool> stopping_{false};
  std::thread thread_;
};

}  // namespace haptic::test
