// The state sender against a real client socket on loopback: in lockstep a flow-controlled
// subscriber never has more than its window unacknowledged and gets every due tick; one that
// stops acknowledging is sent on without waiting after kAckStallTimeout (counted), and every due
// sample it did not get (overwritten in the ring meanwhile) still takes its sequence number, so
// the client sees the gap.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <thread>
#include <vector>

#include "haptic/wire/datagram.hpp"
#include "net/session_registry.hpp"
#include "net/udp_endpoint.hpp"
#include "runtime/sample_ring.hpp"

namespace haptic::net {
namespace {

using namespace std::chrono_literals;

/// A client's UDP socket on 127.0.0.1 and what it read.
class ClientSocket {
 public:
  ClientSocket() {
    fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    // Room for a ring's worth of States sent at once (as root past net.core.rmem_max).
    const int bytes = 8 << 20;
    if (::setsockopt(fd_, SOL_SOCKET, SO_RCVBUFFORCE, &bytes, sizeof bytes) != 0) {
      ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &bytes, sizeof bytes);
    }
    sockaddr_in any{};
    any.sin_family = AF_INET;
    any.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(::bind(fd_, reinterpret_cast<sockaddr*>(&any), sizeof any), 0);
    socklen_t length = sizeof address_.storage;
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&address_.storage), &length);
    address_.length = length;
  }
  ~ClientSocket() { ::close(fd_); }
  const UdpAddress& address() const { return address_; }

  /// Reads one State within `timeout`; false when none came.
  bool read(const wire::Key& key, wire::Header& header, wire::StatePayload& state,
            std::chrono::milliseconds timeout) {
    pollfd pfd{fd_, POLLIN, 0};
    if (::poll(&pfd, 1, static_cast<int>(timeout.count())) <= 0) return false;
    std::array<std::uint8_t, 2048> bytes{};
    const ssize_t n = ::recv(fd_, bytes.data(), bytes.size(), 0);
    if (n <= 0) return false;
    return wire::decode_state({bytes.data(), static_cast<std::size_t>(n)}, key, header, state) ==
           wire::DecodeError::kNone;
  }

  /// Sends a heartbeat acknowledging `last_state_sequence` to the server's port.
  void acknowledge(std::uint16_t server_port, std::uint64_t session_id, const wire::Key& key,
                   std::uint64_t heartbeat_sequence, std::uint64_t last_state_sequence) {
    wire::Header header;
    header.session_id = session_id;
    header.sequence = heartbeat_sequence;
    wire::HeartbeatPayload heartbeat;
    heartbeat.last_state_sequence = last_state_sequence;
    std::array<std::uint8_t, wire::kHeartbeatDatagramSize> bytes{};
    wire::encode_heartbeat(header, heartbeat, key, bytes);
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(server_port);
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::sendto(fd_, bytes.data(), bytes.size(), 0, reinterpret_cast<sockaddr*>(&to), sizeof to);
  }

 private:
  int fd_ = -1;
  UdpAddress address_;
};

/// A lockstep sender (no time origin) with one port's ring, and a session subscribed every tick
/// from tick 1 with `window`, its address validated.
struct Harness {
  explicit Harness(std::uint32_t window) : endpoint(registry, {&ring}) {
    endpoint.bind("127.0.0.1", 0);
    session = *registry.open("reader", 0, "127.0.0.1");
    const HeartbeatOutcome challenge = registry.on_heartbeat(session.id, 1, client.address());
    EXPECT_TRUE(registry.on_path_response(session.id, 2, challenge.nonce, client.address()));
    EXPECT_TRUE(registry.subscribe(session.id, 1, 1, window).value_or(false));
    endpoint.start();
  }
  ~Harness() {
    ring.stop();
    endpoint.stop();
  }
  void publish(std::uint64_t tick) {
    runtime::TickSample sample;
    sample.tick = tick;
    sample.time_ns = static_cast<std::int64_t>(tick) * 1'000'000;
    ring.publish(sample);
  }

  SessionRegistry registry{4, std::chrono::milliseconds(60'000)};
  runtime::SampleRing ring;
  ClientSocket client;
  UdpEndpoint endpoint;
  SessionInfo session;
};

TEST(LockstepFlowControl, EveryDueTickArrivesAndNoMoreThanTheWindowIsEverUnacknowledged) {
  constexpr std::uint32_t kWindow = 16;
  constexpr std::uint64_t kTicks = 3000;
  Harness h(kWindow);
  std::atomic<std::uint64_t> acknowledged{0};
  std::vector<std::uint64_t> ticks;
  std::uint64_t most_unacknowledged = 0;
  bool sequence_is_tick = true;
  std::thread reader([&] {
    std::uint64_t heartbeat = 10;
    wire::Header header;
    wire::StatePayload state;
    while (ticks.size() < kTicks && h.client.read(h.session.key, header, state, 5000ms)) {
      ticks.push_back(state.tick);
      sequence_is_tick = sequence_is_tick && header.sequence == state.tick;
      most_unacknowledged = std::max(most_unacknowledged, header.sequence - acknowledged.load());
      if (header.sequence % 4 == 0) {  // a quarter window read: acknowledge, as the SDK does
        acknowledged.store(header.sequence);
        h.client.acknowledge(h.endpoint.port(), h.session.id, h.session.key, ++heartbeat, header.sequence);
      }
    }
  });
  // As a lockstep Step does: never more than half a ring ahead of the sender.
  for (std::uint64_t tick = 1; tick <= kTicks; ++tick) {
    if (tick > runtime::SampleRing::kCapacity / 2) {
      ASSERT_TRUE(h.endpoint.wait_sent_through(tick - runtime::SampleRing::kCapacity / 2, 10s));
    }
    h.publish(tick);
  }
  reader.join();
  ASSERT_EQ(ticks.size(), kTicks);
  for (std::uint64_t i = 0; i < kTicks; ++i) ASSERT_EQ(ticks[i], i + 1);
  EXPECT_TRUE(sequence_is_tick);
  EXPECT_LE(most_unacknowledged, kWindow);
  EXPECT_EQ(h.endpoint.counters().samples_missed.load(), 0u);
  EXPECT_EQ(h.endpoint.counters().ack_stalls.load(), 0u);
}

TEST(LockstepFlowControl, AReaderThatStopsAcknowledgingIsSentOnAndItsLossesAreNumbered) {
  constexpr std::uint32_t kWindow = 16;
  constexpr std::uint64_t kTicks = 3000;
  Harness h(kWindow);
  std::vector<std::uint64_t> ticks;
  bool sequence_is_tick = true;
  wire::Header header;
  wire::StatePayload state;
  // One window's worth, read and never acknowledged.
  for (std::uint64_t tick = 1; tick <= kWindow; ++tick) h.publish(tick);
  while (ticks.size() < kWindow && h.client.read(h.session.key, header, state, 10s)) {
    ticks.push_back(state.tick);
    sequence_is_tick = sequence_is_tick && header.sequence == state.tick;
  }
  ASSERT_EQ(ticks.size(), kWindow) << "sent " << h.endpoint.counters().sent.load() << " errors "
                                   << h.endpoint.counters().send_errors.load() << " missed "
                                   << h.endpoint.counters().samples_missed.load();
  // The rest at once: the sender waits on the full window, and the ring laps it meanwhile.
  for (std::uint64_t tick = kWindow + 1; tick <= kTicks; ++tick) h.publish(tick);
  // It sends on after kAckStallTimeout: wait for the last tick (or give up after ten).
  while (h.client.read(h.session.key, header, state, 10s)) {
    ticks.push_back(state.tick);
    sequence_is_tick = sequence_is_tick && header.sequence == state.tick;
    if (state.tick == kTicks) break;
  }
  ASSERT_FALSE(ticks.empty());
  EXPECT_EQ(ticks.back(), kTicks);
  EXPECT_EQ(ticks.size(), std::size_t{kWindow} + runtime::SampleRing::kCapacity)
      << "the window before the stall, then what the ring still held";
  // Every due tick took its number: the client sees each one it never got as a gap.
  EXPECT_TRUE(sequence_is_tick);
  EXPECT_EQ(h.endpoint.counters().samples_missed.load() + ticks.size(), kTicks);
  EXPECT_EQ(h.registry.client_statistics().at(0).samples_unsent, h.endpoint.counters().samples_missed.load());
  EXPECT_EQ(h.endpoint.counters().ack_stalls.load(), 1u);
}

}  // namespace
}  // namespace haptic::net
