#pragma once
// The SDK's end of the UDP data plane: one socket on an ephemeral port, heartbeats to the server
// (which answers the address they come from), authenticated State datagrams in. One asio thread.

#include <asio.hpp>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <thread>

#include "clock_sync.hpp"
#include "haptic/types.hpp"
#include "haptic/wire/datagram.hpp"

namespace haptic::detail {

class UdpLink {
 public:
  /// Resolves host:port; throws ConnectionError if it cannot.
  UdpLink(const std::string& host, std::uint16_t port, std::uint64_t session_id,
          const wire::Key& key, std::chrono::milliseconds heartbeat_period);
  ~UdpLink();
  UdpLink(const UdpLink&) = delete;
  UdpLink& operator=(const UdpLink&) = delete;

  void set_heartbeats_enabled(bool enabled) { heartbeats_enabled_ = enabled; }
  /// Sends one extra heartbeat from the UDP thread (any thread may call this).
  void send_heartbeat_soon() {
    asio::post(io_, [this] { send_heartbeat(); });
  }
  /// Points the link at a new session (the server restarted and the session was reopened):
  /// heartbeats go to `port` with the new id and key, and what belonged to the old session's
  /// stream (the newest sample, the clock estimate, the sequence) starts afresh; the socket, the
  /// callback and the counters stay. Blocks until the UDP thread has switched.
  void rebind(std::uint16_t port, std::uint64_t session_id, const wire::Key& key);
  /// The server's ticks start again from 1 (a lockstep reset, whose reply has just come): reads
  /// what has already reached the socket (the old run's last datagrams, which the server sent
  /// before replying: on one host, all of them), then forgets the old run's ticks, newest sample
  /// and clock, and drops any later datagram numbered as one already seen. Blocks until the UDP
  /// thread has done so.
  void restart_ticks();
  /// The client (re)subscribed: the server may number from 1 again.
  void new_subscription();
  /// When the last authenticated datagram arrived (a State or a path challenge); none before one.
  std::optional<std::chrono::steady_clock::time_point> last_heard() const;
  /// Adds `samples` to ReceiveCounters::lost (the samples an outage cost, estimated by its owner).
  void count_lost(std::uint64_t samples);
  void on_state(std::function<void(const State&)> callback);
  /// Offers a sample that came another way (the Step reply); kept if it is the newest.
  void offer(const State& state);
  bool poll(State& out, std::chrono::milliseconds timeout);
  bool wait_for_tick(std::uint64_t tick, State& out, std::chrono::milliseconds timeout);
  std::optional<std::chrono::nanoseconds> clock_offset() const;
  std::optional<double> clock_drift() const;
  std::optional<double> server_time_at(std::chrono::steady_clock::time_point local) const;
  ReceiveCounters counters() const;
  /// Whether the calling thread is the one that runs the on_state callback.
  bool on_callback_thread() const { return std::this_thread::get_id() == dispatcher_.get_id(); }

 private:
  void send_heartbeat();
  void schedule_heartbeat();
  void start_receive();
  /// One wake-up: the datagram already in the buffer and every one queued behind it; only the
  /// newest State is handed out (the others are counted as skipped).
  void receive_batch(std::size_t first_size);
  /// Decodes the datagram in the buffer: answers a challenge, or keeps a State if it is the
  /// newest so far (`accepted` counts States taken).
  /// What one wake-up read: its time, the newest State taken, how many were taken.
  struct Batch {
    std::chrono::steady_clock::time_point received_at;
    std::optional<State> newest;
    std::uint64_t accepted = 0;
  };
  void take(std::span<const std::uint8_t> datagram, Batch& batch);
  /// Reads and takes every datagram already queued on the socket, into `buffer`.
  void drain(std::span<std::uint8_t> buffer, Batch& batch);
  /// Makes the batch's newest State the latest and hands it to the callback's thread.
  void hand_out(const Batch& batch);
  /// Echoes a PathChallenge's nonce (the server sends state only where one was answered).
  void answer_challenge(std::span<const std::uint8_t> datagram);
  /// Forgets the newest tick, sample and clock estimate (ticks restarted). Holds mutex_.
  void forget_ticks_locked();

  asio::io_context io_;
  asio::ip::udp::socket socket_;
  asio::ip::udp::endpoint server_;
  asio::ip::udp::endpoint sender_;
  asio::steady_timer heartbeat_timer_;
  std::chrono::milliseconds heartbeat_period_;
  std::uint64_t session_id_;
  wire::Key key_;
  std::uint64_t heartbeat_sequence_ = 0;  // io thread only
  std::array<std::uint8_t, 2048> receive_buffer_{};
  std::atomic<bool> heartbeats_enabled_{true};

  mutable std::mutex mutex_;
  std::condition_variable arrived_;
  State latest_;                       // guarded by mutex_
  bool have_latest_ = false;           // guarded by mutex_
  std::optional<std::uint64_t> last_polled_tick_;  // guarded by mutex_; none before the first
  std::uint64_t last_sequence_ = 0;    // guarded by mutex_
  std::uint64_t seen_window_ = 0;      // guarded by mutex_: bit i set: last_sequence_ - i arrived
  std::uint64_t stale_through_ = 0;    // guarded by mutex_: sequences of a run before a reset
  std::uint64_t newest_tick_ = 0;      // guarded by mutex_: of the States taken
  ClockSync clock_;                    // guarded by mutex_
  std::optional<std::chrono::steady_clock::time_point> last_heard_;  // guarded by mutex_
  ReceiveCounters counters_;           // guarded by mutex_
  // The heartbeat's report (guarded by mutex_): counters_ as the current session started, and the
  // newest State's server stamp with its arrival (the round-trip echo).
  std::uint64_t session_accepted_base_ = 0;
  std::uint64_t session_lost_base_ = 0;
  std::int64_t echo_state_time_ns_ = 0;
  std::chrono::steady_clock::time_point echo_received_at_{};

  /// The callback's own thread: a slow callback must not hold up the io thread, which sends
  /// the heartbeats that keep the lease. It is handed the newest State (conflated).
  void dispatch_loop();

  std::mutex callback_mutex_;  // held while the callback runs, so on_state({}) waits it out
  std::function<void(const State&)> callback_;  // guarded by callback_mutex_
  std::atomic<bool> has_callback_{false};
  mutable std::mutex dispatch_mutex_;
  std::condition_variable dispatch_ready_;
  std::optional<State> pending_;       // guarded by dispatch_mutex_: the next State for the callback
  bool stopping_dispatch_ = false;     // guarded by dispatch_mutex_
  std::uint64_t callback_skipped_ = 0; // guarded by dispatch_mutex_

  std::thread thread_;
  std::thread dispatcher_;
};

}  // namespace haptic::detail
