#include "net/session_registry.hpp"

#include <arpa/inet.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <string_view>

namespace haptic::net {
namespace {

bool same_address(const UdpAddress& a, const UdpAddress& b) {
  return a.length == b.length && std::memcmp(&a.storage, &b.storage, a.length) == 0;
}

}  // namespace

std::string peer_host(const std::string& grpc_peer) {
  std::string rest = grpc_peer;
  for (const char* scheme : {"ipv4:", "ipv6:"}) {
    if (rest.rfind(scheme, 0) == 0) {
      rest = rest.substr(std::string(scheme).size());
      break;
    }
  }
  if (rest.size() == grpc_peer.size()) return grpc_peer;  // unix:, fd:, ...
  for (const auto& [escaped, plain] : {std::pair{"%5B", "["}, {"%5D", "]"}}) {
    for (auto at = rest.find(escaped); at != std::string::npos; at = rest.find(escaped)) {
      rest.replace(at, 3, plain);
    }
  }
  std::string host;
  if (!rest.empty() && rest.front() == '[') {
    host = rest.substr(1, rest.find(']') - 1);
  } else {
    host = rest.substr(0, rest.rfind(':'));
  }
  constexpr std::string_view kMapped = "::ffff:";
  if (host.rfind(kMapped, 0) == 0 && host.find('.') != std::string::npos) {
    host = host.substr(kMapped.size());
  }
  return host;
}

SessionRegistry::SessionRegistry(const SessionLimits& limits) : limits_(limits) {}

SessionRegistry::SessionRegistry(std::uint32_t max_sessions, std::chrono::milliseconds lease_timeout)
    : limits_{max_sessions, max_sessions, max_sessions, lease_timeout} {}

std::optional<SessionInfo> SessionRegistry::open(const std::string& client_name,
                                                 std::uint32_t device_index,
                                                 const std::string& peer, std::string* refusal,
                                                 const Caller& caller) {
  // Ids and keys come from the OS entropy source: a session id is also the capability that lets a
  // client change its own objects, so it must not be guessable.
  std::random_device entropy;
  auto random64 = [&entropy] {
    return (static_cast<std::uint64_t>(entropy()) << 32) ^ static_cast<std::uint64_t>(entropy());
  };
  std::lock_guard lock(mutex_);
  const SteadyClock::time_point now = SteadyClock::now();
  if (opens_by_peer_.size() > 4096) {  // forget hosts idle for a minute (their buckets are full)
    std::erase_if(opens_by_peer_, [&](const auto& entry) { return now - entry.second.at > std::chrono::minutes(1); });
  }
  const double burst = limits_.session_open_burst;
  auto [budget, added] = opens_by_peer_.try_emplace(peer, TokenBucket{burst, now});
  if (!budget->second.take(limits_.session_open_rate_hz, burst, now)) {
    if (refusal) {
      *refusal = "too many sessions opened from " + (peer.empty() ? std::string("this host") : peer) +
                 ": at most " + std::to_string(limits_.session_open_rate_hz) + " a second after a burst of " +
                 std::to_string(limits_.session_open_burst) +
                 " (session_open_rate_per_peer, session_open_burst_per_peer)";
    }
    return std::nullopt;
  }
  if (sessions_.size() >= limits_.max_sessions) {
    if (refusal) {
      *refusal = "too many sessions open: the server's most is " +
                 std::to_string(limits_.max_sessions) + " (max_sessions)";
    }
    return std::nullopt;
  }
  const auto from_peer = static_cast<std::uint32_t>(std::count_if(
      sessions_.begin(), sessions_.end(), [&](const auto& entry) { return entry.second.info.peer == peer; }));
  if (from_peer >= limits_.max_sessions_per_peer) {
    if (refusal) {
      *refusal = "too many sessions open from " + (peer.empty() ? std::string("this host") : peer) +
                 ": " + std::to_string(from_peer) + ", the most one host may hold (" +
                 std::to_string(limits_.max_sessions_per_peer) + ", max_sessions_per_peer)";
    }
    return std::nullopt;
  }
  if (limits_.max_sessions_per_token > 0 && !caller.token_name.empty()) {
    const auto with_token = static_cast<std::uint32_t>(std::count_if(
        sessions_.begin(), sessions_.end(),
        [&](const auto& entry) { return entry.second.info.caller.token_name == caller.token_name; }));
    if (with_token >= limits_.max_sessions_per_token) {
      if (refusal) {
        *refusal = "too many sessions open with token '" + caller.token_name + "': " +
                   std::to_string(with_token) + ", the most one token may hold from all hosts together (" +
                   std::to_string(limits_.max_sessions_per_token) + ", max_sessions_per_token)";
      }
      return std::nullopt;
    }
  }
  Session session;
  do {
    session.info.id = random64() & ~kRemoteSiteOwnerBit;
  } while (session.info.id == 0 || sessions_.contains(session.info.id));
  session.info.client_name = client_name;
  session.info.device_index = device_index;
  session.info.peer = peer;
  session.info.caller = caller;
  for (auto& byte : session.info.key) byte = static_cast<std::uint8_t>(entropy());
  for (auto& byte : session.info.secret) byte = static_cast<std::uint8_t>(entropy());
  session.last_seen = SteadyClock::now();
  session.info.opened = session.last_seen;
  session.heartbeats.at = session.last_seen;
  SessionInfo info = session.info;
  sessions_.emplace(info.id, std::move(session));
  return info;
}

std::vector<SessionInfo> SessionRegistry::list() const {
  std::lock_guard lock(mutex_);
  std::vector<SessionInfo> out;
  out.reserve(sessions_.size());
  for (const auto& [id, session] : sessions_) out.push_back(session.info);
  return out;
}

std::vector<ClientStatistics> SessionRegistry::client_statistics(SteadyClock::time_point now) const {
  std::lock_guard lock(mutex_);
  std::vector<ClientStatistics> out;
  out.reserve(sessions_.size());
  for (const auto& [id, session] : sessions_) {
    ClientStatistics& client = out.emplace_back();
    client.info = session.info;
    client.decimation = session.decimation;
    client.datagrams_sent = session.sent->load(std::memory_order_relaxed);
    client.heartbeats = session.heartbeats_accepted;
    client.states_received = session.report.states_received;
    client.states_lost = session.report.states_lost;
    client.ack_window = session.ack_window;
    client.acknowledged_sequence = session.acknowledged->load(std::memory_order_relaxed);
    client.samples_unsent = session.unsent->load(std::memory_order_relaxed);
    if (session.last_heartbeat) client.since_heartbeat = now - *session.last_heartbeat;
    const std::size_t kept = std::min(session.round_trip_count, kRoundTripWindow);
    const std::size_t oldest = session.round_trip_count - kept;
    for (std::size_t i = 0; i < kept; ++i) {
      client.round_trips_ns.push_back(session.round_trips[(oldest + i) % kRoundTripWindow]);
    }
  }
  return out;
}

bool SessionRegistry::end(std::uint64_t session_id, const std::string& reason) {
  std::lock_guard lock(mutex_);
  if (sessions_.erase(session_id) == 0) return false;
  ++version_;
  constexpr std::size_t kRemembered = 1024;
  if (ended_order_.size() >= kRemembered) {
    ended_.erase(ended_order_.front());
    ended_order_.erase(ended_order_.begin());
  }
  ended_[session_id] = reason;
  ended_order_.push_back(session_id);
  return true;
}

std::optional<std::string> SessionRegistry::ended_reason(std::uint64_t session_id) const {
  std::lock_guard lock(mutex_);
  const auto found = ended_.find(session_id);
  if (found == ended_.end()) return std::nullopt;
  return found->second;
}

bool SessionRegistry::close(std::uint64_t session_id) {
  std::lock_guard lock(mutex_);
  if (sessions_.erase(session_id) == 0) return false;
  ++version_;
  return true;
}

Access SessionRegistry::authorize(std::uint64_t session_id, std::span<const std::uint8_t> secret) {
  std::lock_guard lock(mutex_);
  auto it = sessions_.find(session_id);
  if (it == sessions_.end()) return Access::kNoSuchSession;
  const SessionSecret& own = it->second.info.secret;
  // Every byte is compared whatever the first difference, so the time taken does not tell a
  // guesser how much of a guess was right.
  std::uint8_t difference = secret.size() == own.size() ? 0 : 1;
  for (std::size_t i = 0; i < own.size(); ++i) {
    difference |= static_cast<std::uint8_t>(own[i] ^ (i < secret.size() ? secret[i] : 0));
  }
  if (difference != 0) return Access::kWrongSecret;
  it->second.last_seen = SteadyClock::now();
  return Access::kGranted;
}

std::optional<wire::Key> SessionRegistry::key_of(std::uint64_t session_id) const {
  std::lock_guard lock(mutex_);
  auto it = sessions_.find(session_id);
  if (it == sessions_.end()) return std::nullopt;
  return it->second.info.key;
}

std::optional<std::uint32_t> SessionRegistry::device_index_of(std::uint64_t session_id) const {
  std::lock_guard lock(mutex_);
  auto it = sessions_.find(session_id);
  if (it == sessions_.end()) return std::nullopt;
  return it->second.info.device_index;
}

std::string SessionRegistry::token_of(std::uint64_t session_id) const {
  std::lock_guard lock(mutex_);
  auto it = sessions_.find(session_id);
  return it == sessions_.end() ? std::string() : it->second.info.caller.token_name;
}

std::string SessionRegistry::peer_of(std::uint64_t session_id) const {
  std::lock_guard lock(mutex_);
  auto it = sessions_.find(session_id);
  return it == sessions_.end() ? std::string() : it->second.info.peer;
}

std::string host_of(const UdpAddress& address) {
  char text[INET6_ADDRSTRLEN] = {};
  const auto* storage = &address.storage;
  if (storage->ss_family == AF_INET) {
    ::inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(storage)->sin_addr, text, sizeof text);
    return text;
  }
  if (storage->ss_family == AF_INET6) {
    const in6_addr& v6 = reinterpret_cast<const sockaddr_in6*>(storage)->sin6_addr;
    if (IN6_IS_ADDR_V4MAPPED(&v6)) {
      ::inet_ntop(AF_INET, &v6.s6_addr[12], text, sizeof text);
    } else {
      ::inet_ntop(AF_INET6, &v6, text, sizeof text);
    }
    return text;
  }
  return {};
}

bool SessionRegistry::source_allowed(const Session& session, const UdpAddress& from) const {
  return limits_.udp_any_source || session.info.peer.empty() || host_of(from) == session.info.peer;
}

HeartbeatOutcome SessionRegistry::on_heartbeat(std::uint64_t session_id, std::uint64_t sequence,
                                               const UdpAddress& from, SteadyClock::time_point now,
                                               const HeartbeatReport& report) {
  using Verdict = HeartbeatOutcome::Verdict;
  std::lock_guard lock(mutex_);
  auto it = sessions_.find(session_id);
  if (it == sessions_.end()) return {Verdict::kStale};
  Session& session = it->second;
  if (!source_allowed(session, from)) return {Verdict::kForeignSource};
  if (sequence <= session.last_heartbeat_sequence) return {Verdict::kStale};
  // An acknowledgement of States not acknowledged before: believed up to the last sequence the
  // sender numbered, so a key holder cannot make more of them than datagrams were sent.
  const std::uint64_t acknowledgeable =
      std::min(report.last_state_sequence, session.sequenced->load(std::memory_order_acquire));
  const bool acknowledges = session.ack_window > 0 && session.decimation > 0 &&
                            acknowledgeable > session.acknowledged->load(std::memory_order_relaxed);
  if (!acknowledges && !session.heartbeats.take(kHeartbeatRateHz, kHeartbeatBurst, now)) {
    return {Verdict::kRateLimited};
  }
  if (acknowledges) session.acknowledged->store(acknowledgeable, std::memory_order_release);
  session.last_heartbeat_sequence = sequence;
  session.last_seen = now;
  ++session.heartbeats_accepted;
  session.last_heartbeat = now;
  session.report = report;
  if (report.round_trip_ns) {
    session.round_trips[session.round_trip_count % kRoundTripWindow] = *report.round_trip_ns;
    ++session.round_trip_count;
  }
  if (session.address && same_address(*session.address, from)) return {Verdict::kAccepted};
  // A new address (the first, or the client moved): state keeps going where it went, if
  // anywhere, until this one answers a challenge. One challenge per address per interval.
  if (session.candidate && same_address(*session.candidate, from) &&
      now - session.challenged_at < kChallengeInterval) {
    return {Verdict::kAccepted};
  }
  // The nonce must be unpredictable to the key holder itself: it is what a spoofer, who has the
  // key but does not receive at the address it names, cannot echo.
  std::random_device entropy;
  session.candidate = from;
  session.challenge_nonce =
      (static_cast<std::uint64_t>(entropy()) << 32) ^ static_cast<std::uint64_t>(entropy());
  session.challenged_at = now;
  return {Verdict::kChallenge, session.challenge_nonce};
}

bool SessionRegistry::on_path_response(std::uint64_t session_id, std::uint64_t sequence,
                                       std::uint64_t nonce, const UdpAddress& from) {
  std::lock_guard lock(mutex_);
  auto it = sessions_.find(session_id);
  if (it == sessions_.end()) return false;
  Session& session = it->second;
  if (!source_allowed(session, from) || sequence <= session.last_heartbeat_sequence) return false;
  if (!session.candidate || !same_address(*session.candidate, from) ||
      nonce != session.challenge_nonce) {
    return false;
  }
  session.last_heartbeat_sequence = sequence;
  session.last_seen = SteadyClock::now();
  session.address = from;
  session.candidate.reset();
  ++version_;
  return true;
}

std::optional<bool> SessionRegistry::subscribe(std::uint64_t session_id, std::uint32_t decimation,
                                               std::uint64_t first_tick, std::uint32_t ack_window) {
  std::lock_guard lock(mutex_);
  auto it = sessions_.find(session_id);
  if (it == sessions_.end()) return std::nullopt;
  if (it->second.decimation == 0 && decimation > 0) {
    // A stream started afresh numbers from 1 (the sender holds no subscriber of this session
    // while its decimation is 0, so nothing else writes these now).
    it->second.sequenced->store(0, std::memory_order_release);
    it->second.acknowledged->store(0, std::memory_order_release);
  }
  it->second.ack_window = decimation > 0 ? ack_window : 0;
  it->second.decimation = decimation;
  it->second.first_tick = first_tick;
  it->second.last_seen = SteadyClock::now();
  ++version_;
  return it->second.address.has_value();
}

void SessionRegistry::restart_ticks() {
  std::lock_guard lock(mutex_);
  for (auto& [id, session] : sessions_) session.first_tick = 0;
  ++version_;
}

std::vector<std::uint64_t> SessionRegistry::expire(SteadyClock::time_point now) {
  std::vector<std::uint64_t> expired;
  std::lock_guard lock(mutex_);
  for (auto it = sessions_.begin(); it != sessions_.end();) {
    if (now - it->second.last_seen > limits_.lease_timeout) {
      expired.push_back(it->first);
      it = sessions_.erase(it);
      ++version_;
    } else {
      ++it;
    }
  }
  return expired;
}

std::uint64_t SessionRegistry::subscribers_version() const {
  std::lock_guard lock(mutex_);
  return version_;
}

std::vector<Subscriber> SessionRegistry::subscribers() const {
  std::vector<Subscriber> out;
  subscribers(out);
  return out;
}

void SessionRegistry::subscribers(std::vector<Subscriber>& out) const {
  out.clear();
  std::lock_guard lock(mutex_);
  for (const auto& [id, session] : sessions_) {
    if (session.decimation == 0 || !session.address) continue;
    out.push_back(Subscriber{id, session.info.key, *session.address, session.decimation,
                             session.first_tick, session.info.device_index, session.sent,
                             session.ack_window, session.sequenced, session.acknowledged,
                             session.unsent});
  }
}

bool SessionRegistry::any_subscribed() const {
  std::lock_guard lock(mutex_);
  return std::any_of(sessions_.begin(), sessions_.end(),
                     [](const auto& entry) { return entry.second.decimation > 0; });
}

std::size_t SessionRegistry::size() const {
  std::lock_guard lock(mutex_);
  return sessions_.size();
}

}  // namespace haptic::net
