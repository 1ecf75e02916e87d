#pragma once
// Client sessions: identity, the UDP key, where to send state, the subscription, and the lease.
// Thread-safe; never used on the loop.

#include <netinet/in.h>
#include <sys/socket.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "haptic/wire/datagram.hpp"
#include "net/access_control.hpp"
#include "net/token_bucket.hpp"

namespace haptic::net {

using SteadyClock = std::chrono::steady_clock;

/// An IPv4 or IPv6 UDP endpoint as the kernel gives it.
struct UdpAddress {
  sockaddr_storage storage{};
  socklen_t length = 0;
};

/// The control plane's capability for a session (haptic/io/session_secret.hpp).
using SessionSecret = std::array<std::uint8_t, 16>;

/// Scene owners with this bit set are other sites of a federation (docs/federation.md), whose
/// shared items this site holds; no session of this server gets such an id.
inline constexpr std::uint64_t kRemoteSiteOwnerBit = std::uint64_t{1} << 63;

struct SessionInfo {
  std::uint64_t id = 0;            // a handle: shown to others (events, energy), grants nothing
  std::string client_name;
  wire::Key key{};                 // the UDP datagrams' SipHash key
  SessionSecret secret{};          // sent with every session-scoped call; never shown to others
  std::uint32_t device_index = 0;  // the device port the session is bound to
  std::string peer;                // the host it was opened from (peer_host()); "" if unknown
  Caller caller;                   // the token it was opened with (none without tokens)
  SteadyClock::time_point opened{};
};

struct SessionLimits {
  std::uint32_t max_sessions = 32;
  std::uint32_t max_sessions_per_peer = 16;  // from any one host, so one cannot take every slot
  std::uint32_t max_sessions_per_token = 16;  // opened with one token, from any hosts; 0: no share
  std::chrono::milliseconds lease_timeout{1000};
  /// False (default): a session's datagrams count only from the host that opened it over gRPC
  /// (its peer), so no one can point a stream at another host at all. True: from anywhere that
  /// passes the path challenge (NATs that give TCP and UDP different public addresses).
  bool udp_any_source = false;
  /// Sessions one host may open: a token bucket of this many a second after a burst of
  /// session_open_burst (a client that opens and closes in a loop cannot churn the server).
  double session_open_rate_hz = 10.0;
  std::uint32_t session_open_burst = 32;
};

/// Heartbeats a session may send: a token bucket, refilled at kHeartbeatRateHz up to
/// kHeartbeatBurst. The SDK sends 10 per second (and a few in a row while it subscribes); past
/// the bucket a heartbeat is dropped unprocessed and counted.
inline constexpr double kHeartbeatRateHz = 100.0;
inline constexpr double kHeartbeatBurst = 20.0;
/// A challenge goes to a new address at most this often per session. Unit: ms.
inline constexpr std::chrono::milliseconds kChallengeInterval{50};

/// What the data plane does with an authenticated heartbeat.
struct HeartbeatOutcome {
  enum class Verdict {
    kAccepted,        // lease renewed; state goes (or will go) to a validated address
    kChallenge,       // lease renewed; the address is new: send it a PathChallenge with `nonce`
    kStale,           // unknown session, or a sequence not above the last (replayed): dropped
    kRateLimited,     // over the session's heartbeat budget: dropped unprocessed
    kForeignSource,   // from another host than the session's peer: dropped, nothing sent
  };
  Verdict verdict = Verdict::kStale;
  std::uint64_t nonce = 0;
};

/// The host of a gRPC peer ("ipv4:10.0.0.7:5123" -> "10.0.0.7", "ipv6:[::1]:5123" -> "::1", an
/// IPv4-mapped IPv6 address as its IPv4 form); the whole string when it has no host part.
std::string peer_host(const std::string& grpc_peer);

/// What a session-scoped call may do.
enum class Access {
  kGranted,        // the session exists and the secret is its own (the lease is renewed)
  kNoSuchSession,  // never opened, closed, or its lease expired
  kWrongSecret,    // the session exists, but the caller is not the client that opened it
};

/// What the data-plane sender needs per subscribed session.
struct Subscriber {
  std::uint64_t session_id = 0;
  wire::Key key{};
  UdpAddress address;
  std::uint32_t decimation = 1;
  std::uint64_t first_tick = 0;  // the stream starts here: ticks before the subscription are not sent
  std::uint32_t device_index = 0;  // whose samples it is sent
  /// The session's count of State datagrams sent; the sender adds to it (relaxed), GetStats reads.
  std::shared_ptr<std::atomic<std::uint64_t>> sent;
  /// Lockstep flow control: at most this many sequence numbers unacknowledged (0: none).
  std::uint32_t ack_window = 0;
  /// The last sequence number the sender gave a due sample of this subscription (sent or not);
  /// the sender alone writes it. Acknowledgements above it are not believed.
  std::shared_ptr<std::atomic<std::uint64_t>> sequenced;
  /// The highest sequence the client has acknowledged (its heartbeats' last_state_sequence, at
  /// most `sequenced`); the receiver writes it.
  std::shared_ptr<std::atomic<std::uint64_t>> acknowledged;
  /// Due samples numbered for it that never left (skipped, missed, refused by the kernel); the
  /// sender adds to it, GetStats reads.
  std::shared_ptr<std::atomic<std::uint64_t>> unsent;
};

/// What a heartbeat reports of the stream as the client receives it (wire::HeartbeatPayload).
struct HeartbeatReport {
  std::uint64_t last_state_sequence = 0;  // the highest State sequence it has received
  std::uint64_t states_received = 0;
  std::uint64_t states_lost = 0;
  /// Server time at receipt − the echoed State's stamp − the client's hold (ns); none in
  /// lockstep, before any State, or when the echo makes no sense (negative, over a minute).
  std::optional<std::int64_t> round_trip_ns;
};

/// One client as GetStats shows it.
struct ClientStatistics {
  SessionInfo info;
  std::uint32_t decimation = 0;        // 0: not subscribed
  std::uint64_t datagrams_sent = 0;    // State datagrams sent to it
  std::uint64_t heartbeats = 0;        // heartbeats accepted
  std::uint64_t states_received = 0;   // as its last heartbeat reported
  std::uint64_t states_lost = 0;
  std::uint32_t ack_window = 0;              // lockstep flow control granted; 0: none
  std::uint64_t acknowledged_sequence = 0;   // the highest sequence it has acknowledged
  std::uint64_t samples_unsent = 0;          // numbered for it, never sent
  /// How long ago its last heartbeat arrived; none yet.
  std::optional<SteadyClock::duration> since_heartbeat;
  /// Round trips of its last kRoundTripWindow heartbeats (ns), in arrival order.
  std::vector<std::int64_t> round_trips_ns;
};

/// Round-trip samples kept per session: 25.6 s of the SDK's 10 heartbeats a second.
inline constexpr std::size_t kRoundTripWindow = 256;

class SessionRegistry {
 public:
  explicit SessionRegistry(const SessionLimits& limits);
  /// Every host may open all max_sessions.
  SessionRegistry(std::uint32_t max_sessions, std::chrono::milliseconds lease_timeout);

  /// Opens a session for a client on host `peer`, bound to device port `device_index`, with a
  /// fresh random id, secret and key; nullopt when max_sessions are open, or max_sessions_per_peer
  /// from that host (`refusal`, when given, then names the limit).
  std::optional<SessionInfo> open(const std::string& client_name, std::uint32_t device_index = 0,
                                  const std::string& peer = {}, std::string* refusal = nullptr,
                                  const Caller& caller = {});
  /// Removes the session; false if it did not exist.
  bool close(std::uint64_t session_id);
  /// Closes the session for good: its client is told why (ended_reason) instead of "no such
  /// session", so that it does not open another (KickSession, an expired token). The last 1024
  /// such endings are remembered.
  bool end(std::uint64_t session_id, const std::string& reason);
  /// Why a session was ended for good; nullopt if it was not (or long ago).
  std::optional<std::string> ended_reason(std::uint64_t session_id) const;
  /// Checks that `secret` is the session's own (in constant time) and, if so, renews the lease.
  Access authorize(std::uint64_t session_id, std::span<const std::uint8_t> secret);
  std::optional<wire::Key> key_of(std::uint64_t session_id) const;
  /// The device port the session is bound to; nullopt if the session does not exist.
  std::optional<std::uint32_t> device_index_of(std::uint64_t session_id) const;
  /// The host it was opened from (peer_host()'s form); "" if the session does not exist.
  std::string peer_of(std::uint64_t session_id) const;
  /// The name of the token it was opened with; "" without tokens, or if it does not exist.
  std::string token_of(std::uint64_t session_id) const;

  /// A heartbeat authenticated with the session's key, from `from`. Renews the lease unless it is
  /// refused (see HeartbeatOutcome). State only ever goes to an address that has answered a
  /// challenge: a heartbeat from any other asks for one to be sent there.
  /// `report` is kept when the heartbeat is (not when refused). A flow-controlled subscription's
  /// heartbeat that acknowledges States not acknowledged before (report.last_state_sequence, up
  /// to the last sequence numbered) is not charged to the heartbeat budget: the SDK sends one per
  /// quarter window it reads, so acknowledgements come at most one per datagram sent.
  HeartbeatOutcome on_heartbeat(std::uint64_t session_id, std::uint64_t sequence,
                                const UdpAddress& from, SteadyClock::time_point now = SteadyClock::now(),
                                const HeartbeatReport& report = {});
  /// A PathResponse authenticated with the session's key: if it comes from the challenged
  /// address with its nonce (and a fresh sequence), that address is where state goes from now on.
  bool on_path_response(std::uint64_t session_id, std::uint64_t sequence, std::uint64_t nonce,
                        const UdpAddress& from);

  /// Sets the state-stream decimation (0 stops it), streaming from tick `first_tick` on (the
  /// sender may still be catching up with older ticks; those are not this subscription's), with
  /// lockstep flow control over `ack_window` sequence numbers (0: none); a stream started afresh
  /// numbers from 1. nullopt if the session does not exist, else whether its UDP address is
  /// validated yet.
  std::optional<bool> subscribe(std::uint64_t session_id, std::uint32_t decimation,
                                std::uint64_t first_tick = 0, std::uint32_t ack_window = 0);

  /// A lockstep reset: the ticks start again, so every subscription streams from the first.
  void restart_ticks();

  /// Removes and returns the sessions whose lease ran out at `now`.
  std::vector<std::uint64_t> expire(SteadyClock::time_point now);

  /// Changes whenever the subscriber list would change; lets the sender copy it only then.
  std::uint64_t subscribers_version() const;
  std::vector<Subscriber> subscribers() const;
  /// The same into `out`, reusing its storage: the real-time sender, which reserves room for
  /// max_sessions() once, refills it without allocating.
  void subscribers(std::vector<Subscriber>& out) const;
  std::uint32_t max_sessions() const { return limits_.max_sessions; }
  /// Whether any session is subscribed to the state stream now.
  bool any_subscribed() const;

  std::size_t size() const;
  /// Every open session (ListSessions), in id order.
  std::vector<SessionInfo> list() const;
  /// Every open session's traffic (GetStats), in id order.
  std::vector<ClientStatistics> client_statistics(SteadyClock::time_point now = SteadyClock::now()) const;
  std::chrono::milliseconds lease_timeout() const { return limits_.lease_timeout; }

 private:
  struct Session {
    SessionInfo info;
    SteadyClock::time_point last_seen;
    std::optional<UdpAddress> address;    // validated: where state goes
    std::optional<UdpAddress> candidate;  // heard from, challenged, not yet validated
    std::uint64_t challenge_nonce = 0;
    SteadyClock::time_point challenged_at;
    TokenBucket heartbeats{kHeartbeatBurst};
    std::uint64_t last_heartbeat_sequence = 0;  // heartbeats and path responses share it
    std::uint32_t decimation = 0;
    std::uint64_t first_tick = 0;
    std::shared_ptr<std::atomic<std::uint64_t>> sent = std::make_shared<std::atomic<std::uint64_t>>(0);
    std::uint32_t ack_window = 0;
    std::shared_ptr<std::atomic<std::uint64_t>> sequenced = std::make_shared<std::atomic<std::uint64_t>>(0);
    std::shared_ptr<std::atomic<std::uint64_t>> acknowledged = std::make_shared<std::atomic<std::uint64_t>>(0);
    std::shared_ptr<std::atomic<std::uint64_t>> unsent = std::make_shared<std::atomic<std::uint64_t>>(0);
    std::uint64_t heartbeats_accepted = 0;
    std::optional<SteadyClock::time_point> last_heartbeat;
    HeartbeatReport report;
    std::array<std::int64_t, kRoundTripWindow> round_trips{};  // a ring
    std::size_t round_trip_count = 0;                          // samples ever kept
  };

  mutable std::mutex mutex_;
  std::map<std::uint64_t, Session> sessions_;
  std::map<std::string, TokenBucket> opens_by_peer_;
  std::map<std::uint64_t, std::string> ended_;  // sessions ended for good, and why
  std::vector<std::uint64_t> ended_order_;      // oldest first, to forget past 1024  // each host's session-opening budget
  SessionLimits limits_;
  std::uint64_t version_ = 0;

  /// False when the session only takes datagrams from its peer's host and `from` is another.
  bool source_allowed(const Session& session, const UdpAddress& from) const;
};

/// The host of a UDP address in the form peer_host() gives ("10.0.0.7", "::1").
std::string host_of(const UdpAddress& address);

}  // namespace haptic::net
