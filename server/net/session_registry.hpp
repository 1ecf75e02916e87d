#pragma once
// Client sessions: identity, the UDP key, where to send state, the subscription, and the lease.
// Thread-safe; never used on the loop.

#include <netinet/in.h>
#include <sys/socket.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "haptic/wire/datagram.hpp"

namespace haptic::net {

using SteadyClock = std::chrono::steady_clock;

/// An IPv4 or IPv6 UDP endpoint as the kernel gives it.
struct UdpAddress {
  sockaddr_storage storage{};
  socklen_t length = 0;
};

/// The control plane's capability for a session (haptic/io/session_secret.hpp).
using SessionSecret = std::array<std::uint8_t, 16>;

struct SessionInfo {
  std::uint64_t id = 0;            // a handle: shown to others (events, energy), grants nothing
  std::string client_name;
  wire::Key key{};                 // the UDP datagrams' SipHash key
  SessionSecret secret{};          // sent with every session-scoped call; never shown to others
  std::uint32_t device_index = 0;  // the device port the session is bound to
  std::string peer;                // the host it was opened from (peer_host()); "" if unknown
};

struct SessionLimits {
  std::uint32_t max_sessions = 32;
  std::uint32_t max_sessions_per_peer = 16;  // from any one host, so one cannot take every slot
  std::chrono::milliseconds lease_timeout{1000};
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
};

class SessionRegistry {
 public:
  explicit SessionRegistry(const SessionLimits& limits);
  /// Every host may open all max_sessions.
  SessionRegistry(std::uint32_t max_sessions, std::chrono::milliseconds lease_timeout);

  /// Opens a session for a client on host `peer`, bound to device port `device_index`, with a
  /// fresh random id, secret and key; nullopt when max_sessions are open, or max_sessions_per_peer
  /// from that host (`refusal`, when given, then names the limit).
  std::optional<SessionInfo> open(const std::string& client_name, std::uint32_t device_index = 0,
                                  const std::string& peer = {}, std::string* refusal = nullptr);
  /// Removes the session; false if it did not exist.
  bool close(std::uint64_t session_id);
  /// Checks that `secret` is the session's own (in constant time) and, if so, renews the lease.
  Access authorize(std::uint64_t session_id, std::span<const std::uint8_t> secret);
  /// Renews the lease; false if the session does not exist.
  bool touch(std::uint64_t session_id);
  std::optional<wire::Key> key_of(std::uint64_t session_id) const;
  /// The device port the session is bound to; nullopt if the session does not exist.
  std::optional<std::uint32_t> device_index_of(std::uint64_t session_id) const;

  /// A heartbeat authenticated with the session's key: renews the lease and records the address
  /// state goes to. Rejects (false) a sequence not above the last one (stale or replayed).
  bool on_heartbeat(std::uint64_t session_id, std::uint64_t sequence, const UdpAddress& from);

  /// Sets the state-stream decimation (0 stops it), streaming from tick `first_tick` on (the
  /// sender may still be catching up with older ticks; those are not this subscription's);
  /// nullopt if the session does not exist, else whether its UDP address is known yet.
  std::optional<bool> subscribe(std::uint64_t session_id, std::uint32_t decimation,
                                std::uint64_t first_tick = 0);

  /// Removes and returns the sessions whose lease ran out at `now`.
  std::vector<std::uint64_t> expire(SteadyClock::time_point now);

  /// Changes whenever the subscriber list would change; lets the sender copy it only then.
  std::uint64_t subscribers_version() const;
  std::vector<Subscriber> subscribers() const;

  std::size_t size() const;
  std::chrono::milliseconds lease_timeout() const { return limits_.lease_timeout; }

 private:
  struct Session {
    SessionInfo info;
    SteadyClock::time_point last_seen;
    std::optional<UdpAddress> address;
    std::uint64_t last_heartbeat_sequence = 0;
    std::uint32_t decimation = 0;
    std::uint64_t first_tick = 0;
  };

  mutable std::mutex mutex_;
  std::map<std::uint64_t, Session> sessions_;
  SessionLimits limits_;
  std::uint64_t version_ = 0;
};

}  // namespace haptic::net
