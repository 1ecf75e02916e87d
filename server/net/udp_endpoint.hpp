#pragma once
// The UDP data plane: one socket, one port (container- and NAT-friendly: clients are answered at
// the address their heartbeats come from; the server never connects back).
//
// Two threads: the receiver authenticates heartbeats (unknown session, bad tag, wrong version,
// stale sequence: dropped and counted); the sender wakes on each published tick sample and encodes
// it only for the sessions subscribed at that decimation.

#include <atomic>
#include <cstdint>
#include <string>
#include <thread>

#include "net/session_registry.hpp"
#include "runtime/sample_ring.hpp"

namespace haptic::net {

struct UdpCounters {
  std::atomic<std::uint64_t> sent{0};
  std::atomic<std::uint64_t> send_errors{0};
  std::atomic<std::uint64_t> received{0};      // accepted heartbeats
  std::atomic<std::uint64_t> dropped{0};       // rejected datagrams of any kind
  std::atomic<std::uint64_t> samples_missed{0};  // samples overwritten before the sender read them
};

class UdpEndpoint {
 public:
  UdpEndpoint(SessionRegistry& sessions, runtime::SampleRing& samples);
  ~UdpEndpoint();
  UdpEndpoint(const UdpEndpoint&) = delete;
  UdpEndpoint& operator=(const UdpEndpoint&) = delete;

  /// Binds `address`:`port` (port 0 picks one). Throws std::runtime_error naming what failed.
  void bind(const std::string& address, std::uint16_t port);
  std::uint16_t port() const { return port_; }

  /// Starts the receiver and sender threads.
  void start();
  /// Stops both threads (the sample ring must be stopped or still publishing).
  void stop();

  const UdpCounters& counters() const { return counters_; }

 private:
  void receive_loop();
  void send_loop();

  SessionRegistry& sessions_;
  runtime::SampleRing& samples_;
  int socket_ = -1;
  std::uint16_t port_ = 0;
  std::atomic<bool> stopping_{false};
  std::thread receiver_;
  std::thread sender_;
  UdpCounters counters_;
};

}  // namespace haptic::net
