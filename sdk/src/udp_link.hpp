#pragma once
// The SDK's end of the UDP data plane: one socket on an ephemeral port, heartbeats to the server
// (which answers the address they come from), authenticated State datagrams in. Two threads: the
// receive thread blocks on the socket, reads whatever has queued with recvmmsg, keeps the newest
// State and hands it to the on_state callback itself (one wake-up from the wire to the
// application); an asio thread sends the heartbeats, so a slow callback never costs the lease.

#include <asio.hpp>
#include <sys/socket.h>
#include <time.h>

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "clock_sync.hpp"
#include "haptic/client.hpp"
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
  /// Lockstep flow control: how many State datagrams this link's socket can hold unread (its
  /// receive buffer as the kernel granted it, at a generous 2 KiB each), to ask the server for.
  std::uint32_t ack_window_capacity() const;
  /// The window the server granted (0: none): from now on the receive thread acknowledges, with
  /// a heartbeat, every quarter of it that it has read.
  void set_ack_window(std::uint32_t window) { ack_window_.store(window, std::memory_order_relaxed); }
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
  /// Calls `tap` with every State accepted from now on (on the receive thread, or the thread of a
  /// restart_ticks or rebind that reads the socket; one at a time) until remove_tap(id), which
  /// waits out a call in progress.
  void add_tap(std::uint64_t id, std::shared_ptr<ReceiveObserver> tap);
  void remove_tap(std::uint64_t id);
  /// Whether the calling thread is the one that runs the on_state callback (the receive thread).
  bool on_callback_thread() const { return std::this_thread::get_id() == receiver_.get_id(); }

 private:
  /// What one wake-up read: its time, the newest State taken, how many were taken, and how many
  /// of those had reached the socket while the callback was running.
  struct Batch {
    std::chrono::steady_clock::time_point received_at;
    std::optional<State> newest;
    std::uint64_t accepted = 0;
    std::uint64_t during_callback = 0;
  };

  void send_heartbeat();
  void schedule_heartbeat();
  /// Flow control (a window granted): sends a heartbeat, which acknowledges the highest sequence
  /// read, once a quarter window has been read since the last one. Receive thread.
  void acknowledge_if_due();
  /// The receive thread: waits on the socket (and the wake-up descriptor, for stopping), reads
  /// under receive_mutex_, and calls the callback with the newest State outside any lock.
  void receive_loop();
  /// Reads every datagram already queued (recvmmsg, up to kMaxDrain) and takes each. Holds
  /// receive_mutex_.
  void drain(Batch& batch);
  /// Decodes one datagram: answers a challenge, or keeps a State if it is the newest so far.
  /// arrived_at: the kernel's receive stamp, if any.
  void take(std::span<const std::uint8_t> datagram,
            std::optional<std::chrono::steady_clock::time_point> arrived_at, Batch& batch);
  /// Makes the batch's newest State the latest and the callback's next. Holds receive_mutex_.
  void hand_out(const Batch& batch);
  /// Calls the callback with the pending State, if any (receive thread, holding no lock but
  /// callback_mutex_).
  void deliver();
  /// Echoes a PathChallenge's nonce (the server sends state only where one was answered).
  void answer_challenge(std::span<const std::uint8_t> datagram);
  /// Forgets the newest tick, sample and clock estimate (ticks restarted). Holds mutex_.
  void forget_ticks_locked();
  /// Sends `bytes` to the server from the socket (any thread).
  void send_to_server(std::span<const std::uint8_t> bytes);

  asio::io_context io_;  // the heartbeat timer's
  // The data socket, a plain descriptor: an asio socket would be registered with the io thread's
  // epoll, and every datagram would wake that thread for nothing.
  int socket_ = -1;
  asio::steady_timer heartbeat_timer_;
  std::chrono::milliseconds heartbeat_period_;
  int wake_fd_ = -1;  // an eventfd: wakes the receive thread to stop
  std::atomic<std::uint64_t> heartbeat_sequence_{0};
  std::atomic<bool> heartbeats_enabled_{true};
  std::atomic<bool> stopping_{false};
  std::atomic<std::uint32_t> ack_window_{0};

  // Who this link speaks for, and where the server is: the receive thread and the heartbeat
  // thread both read them; rebind() changes them.
  mutable std::mutex identity_mutex_;
  asio::ip::udp::endpoint server_;  // guarded by identity_mutex_
  std::uint64_t session_id_;        // guarded by identity_mutex_
  wire::Key key_;                   // guarded by identity_mutex_

  // Held while datagrams are read and taken (by the receive thread, or by restart_ticks and
  // rebind from any thread), never while the callback runs.
  std::mutex receive_mutex_;
  std::optional<State> pending_;  // guarded by receive_mutex_: the callback's next State
  /// recvmmsg's buffers, kBatch datagrams a call (guarded by receive_mutex_; on the heap, 67 KB).
  static constexpr unsigned kBatch = 32;
  struct ReceiveSlot {
    std::array<std::uint8_t, 2048> bytes;
    alignas(cmsghdr) std::array<char, CMSG_SPACE(sizeof(timespec))> control;
    iovec iov;
  };
  struct ReceiveBuffers {
    std::array<ReceiveSlot, kBatch> slots;
    std::array<mmsghdr, kBatch> messages;
  };
  std::unique_ptr<ReceiveBuffers> receive_buffers_ = std::make_unique<ReceiveBuffers>();

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
  // Observers of every accepted State (ClientCore::observe), called in take() under mutex_: a
  // removal then never races a call. Rarely changed; a vector to walk without allocating.
  std::vector<std::pair<std::uint64_t, std::shared_ptr<ReceiveObserver>>> taps_;  // guarded by mutex_
  // The heartbeat's report (guarded by mutex_): counters_ as the current session started, and the
  // newest State's server stamp with its arrival (the round-trip echo).
  std::uint64_t session_accepted_base_ = 0;
  std::uint64_t session_lost_base_ = 0;
  std::uint64_t accepted_at_acknowledgement_ = 0;  // counters_.accepted when last acknowledged
  std::int64_t echo_state_time_ns_ = 0;
  std::chrono::steady_clock::time_point echo_received_at_{};

  // The callback (receive thread). callback_mutex_ is held while it runs, so on_state({}) waits
  // it out. The last call's start and end, to tell States that queued behind it from others.
  std::mutex callback_mutex_;
  std::function<void(const State&)> callback_;  // guarded by callback_mutex_
  std::atomic<bool> has_callback_{false};
  std::atomic<bool> in_callback_{false};
  std::atomic<std::int64_t> callback_started_ns_{0};  // the last call's start, steady ns
  std::atomic<std::int64_t> callback_ended_ns_{0};    // and its end

  std::thread thread_;    // asio: heartbeats
  std::thread receiver_;  // the socket and the callback
};

}  // namespace haptic::detail
