#pragma once
// The UDP data plane: one socket, one port (container- and NAT-friendly: clients are answered at
// the address their heartbeats come from; the server never connects back).
//
// Two threads: the receiver authenticates heartbeats and path responses (unknown session, bad
// tag, wrong version, stale sequence, another host, over the heartbeat budget: dropped and
// counted) and challenges every address a heartbeat comes from before state may go there (a
// challenge is as long as the heartbeat that drew it, at most one per address per 50 ms: no
// reflection, no amplification); the sender wakes on each published tick sample and encodes it
// only for the sessions subscribed at that decimation, each from its own device port's ring.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "net/session_registry.hpp"
#include "runtime/loop_stats.hpp"
#include "runtime/sample_ring.hpp"

namespace haptic::net {

struct UdpCounters {
  std::atomic<std::uint64_t> sent{0};
  std::atomic<std::uint64_t> send_errors{0};
  std::atomic<std::uint64_t> received{0};      // accepted heartbeats and path responses
  std::atomic<std::uint64_t> dropped{0};       // rejected datagrams of any kind, the two below among them
  std::atomic<std::uint64_t> rate_limited{0};  // heartbeats over their session's budget
  std::atomic<std::uint64_t> foreign_source{0};  // from another host than the session's peer
  std::atomic<std::uint64_t> challenges_sent{0};  // PathChallenges to addresses not yet validated
  /// Due samples the ring had overwritten before the sender read them (it was held up for longer
  /// than the ring lasts); each still takes its subscriber's sequence number.
  std::atomic<std::uint64_t> samples_missed{0};
  /// Flow-controlled subscribers the sender stopped waiting for: nothing acknowledged for
  /// kAckStallTimeout while their window was full.
  std::atomic<std::uint64_t> ack_stalls{0};
  /// Due samples not sent because a newer one was ready for the same subscriber (the sender had
  /// fallen behind): conflated, never queued.
  std::atomic<std::uint64_t> samples_skipped{0};
  /// Real time only: from a tick's time stamp to its first datagram leaving (sendto returned).
  runtime::LatenessHistogram send_delay;
};

/// One State datagram to send: subscribers[subscriber] gets tick `tick`.
struct PlannedSend {
  std::size_t subscriber = 0;
  std::uint64_t tick = 0;
  /// This subscriber's due samples conflated away just before this one (real time): each takes a
  /// sequence number, so the client sees the gap as samples lost.
  std::uint64_t skipped_before = 0;
};

/// What the sender sends on a wake-up that finds ticks (last_tick, newest] published: each
/// subscriber's due ticks (every decimation-th, from its first_tick), in tick order. Conflating,
/// only each subscriber's newest due tick; the older due ones are added to `skipped` (and to
/// that send's skipped_before).
void plan_sends(std::span<const Subscriber> subscribers, std::uint64_t last_tick,
                std::uint64_t newest, bool conflate, std::vector<PlannedSend>& out,
                std::uint64_t& skipped);

/// Lockstep flow control: the last tick after `last_tick` that may be sent to `subscriber`
/// without its unacknowledged sequence numbers passing its window, given the last sequence
/// numbered (`sequenced`) and the highest acknowledged. Every due tick takes one number; ticks
/// not due to it are free. Without a window, no limit.
std::uint64_t flow_limit(const Subscriber& subscriber, std::uint64_t sequenced,
                         std::uint64_t acknowledged, std::uint64_t last_tick);

/// How long the sender waits for a flow-controlled subscriber's acknowledgement before sending on
/// without it (counted, UdpCounters::ack_stalls) until it catches up: longer than the SDK's
/// heartbeat period (100 ms), whose heartbeats acknowledge too, so only a client that has
/// stopped reading meets it.
inline constexpr std::chrono::milliseconds kAckStallTimeout{1000};

/// How the State sender thread is scheduled.
struct SenderScheduling {
  int cpu = -1;       // pinned to this CPU; -1: not pinned
  int priority = 0;   // SCHED_FIFO priority; 0: normal scheduling
};

/// What UdpEndpoint::start could not have: empty strings when all was granted.
struct SenderSetup {
  std::string priority_error;
  std::string cpu_error;
};

class UdpEndpoint {
 public:
  /// rings: one per device port, port 0 first; the loop publishes them in that order each tick.
  UdpEndpoint(SessionRegistry& sessions, std::vector<runtime::SampleRing*> rings);
  ~UdpEndpoint();
  UdpEndpoint(const UdpEndpoint&) = delete;
  UdpEndpoint& operator=(const UdpEndpoint&) = delete;

  /// Binds `address`:`port` (port 0 picks one). Throws std::runtime_error naming what failed.
  void bind(const std::string& address, std::uint16_t port);
  std::uint16_t port() const { return port_; }

  /// Starts the receiver and sender threads. With a time origin (the CLOCK_MONOTONIC time of
  /// server time 0, real time only) the sender also measures each tick's send delay, and the
  /// receiver each client's round trip from its heartbeats' echoes. The sender is scheduled as
  /// `scheduling` says (real_time.sender_cpu, sender_priority): by default on the loop's CPU at a
  /// FIFO priority just below the loop's, so it runs the moment the loop sleeps — no other thread
  /// comes first, and no idle CPU has to be woken (on a VM that cost ≈ 70 µs).
  SenderSetup start(std::optional<std::int64_t> time_origin_ns = std::nullopt,
                    SenderScheduling scheduling = {});
  /// Stops both threads (the sample rings must be stopped or still publishing).
  void stop();

  const UdpCounters& counters() const { return counters_; }

  /// Waits (up to `timeout`) until the sender has sent what is due up to tick `tick`: before a
  /// lockstep reset, so that no datagram of the old ticks leaves after it. True when it has.
  bool wait_sent_through(std::uint64_t tick, std::chrono::milliseconds timeout) const;

 private:
  void receive_loop();
  /// One authenticated datagram from `from`; false when it is dropped.
  bool handle_heartbeat(std::span<const std::uint8_t> datagram, const wire::Header& header,
                        const wire::Key& key, const UdpAddress& from);
  bool handle_path_response(std::span<const std::uint8_t> datagram, const wire::Header& header,
                            const wire::Key& key, const UdpAddress& from);
  /// Where the sender starts: the last ring's epoch and newest tick when start() was called.
  struct SendFrom {
    std::uint32_t epoch = 0;
    std::uint64_t tick = 0;
  };
  void send_loop(std::optional<std::int64_t> time_origin_ns, SendFrom from);
  /// Wakes a sender waiting for an acknowledgement (the receiver, after one arrived).
  void acknowledgement_arrived();

  SessionRegistry& sessions_;
  std::vector<runtime::SampleRing*> rings_;
  int socket_ = -1;
  std::uint16_t port_ = 0;
  std::atomic<bool> stopping_{false};
  std::atomic<std::uint64_t> sent_through_{0};  // the sender's last_tick, for wait_sent_through
  // The sender waits here while a flow-controlled subscriber's window is full.
  std::mutex acknowledgement_mutex_;
  std::condition_variable acknowledgement_cv_;
  std::uint64_t acknowledgements_ = 0;  // guarded by acknowledgement_mutex_
  std::optional<std::int64_t> time_origin_ns_;  // set by start() before the threads run
  std::thread receiver_;
  std::thread sender_;
  UdpCounters counters_;
};

}  // namespace haptic::net
