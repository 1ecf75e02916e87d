#include "net/udp_endpoint.hpp"

#include <future>

#include <arpa/inet.h>
#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <future>
#include <optional>
#include <span>
#include <stdexcept>
#include <vector>

#include "haptic/wire/datagram.hpp"
#include "net/read_back.hpp"
#include "runtime/realtime.hpp"

namespace haptic::net {

UdpEndpoint::UdpEndpoint(SessionRegistry& sessions, std::vector<runtime::SampleRing*> rings)
    : sessions_(sessions), rings_(std::move(rings)) {}

UdpEndpoint::~UdpEndpoint() {
  stop();
  if (socket_ >= 0) ::close(socket_);
}

void UdpEndpoint::bind(const std::string& address, std::uint16_t port) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_DGRAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* found = nullptr;
  const std::string service = std::to_string(port);
  if (const int rc = ::getaddrinfo(address.empty() ? nullptr : address.c_str(), service.c_str(),
                                   &hints, &found);
      rc != 0) {
    throw std::runtime_error("udp_address '" + address + "': " + ::gai_strerror(rc));
  }
  std::string last_error = "no address";
  for (addrinfo* ai = found; ai != nullptr; ai = ai->ai_next) {
    const int fd = ::socket(ai->ai_family, ai->ai_socktype | SOCK_CLOEXEC, ai->ai_protocol);
    if (fd < 0) {
      last_error = std::strerror(errno);
      continue;
    }
    if (::bind(fd, ai->ai_addr, ai->ai_addrlen) != 0) {
      last_error = std::strerror(errno);
      ::close(fd);
      continue;
    }
    socket_ = fd;
    break;
  }
  ::freeaddrinfo(found);
  if (socket_ < 0) {
    throw std::runtime_error("cannot bind UDP " + address + ":" + service + ": " + last_error);
  }
  sockaddr_storage bound{};
  socklen_t length = sizeof(bound);
  ::getsockname(socket_, reinterpret_cast<sockaddr*>(&bound), &length);
  port_ = ntohs(bound.ss_family == AF_INET6 ? reinterpret_cast<sockaddr_in6*>(&bound)->sin6_port
                                            : reinterpret_cast<sockaddr_in*>(&bound)->sin_port);
}

SenderSetup UdpEndpoint::start(std::optional<std::int64_t> time_origin_ns,
                                            SenderScheduling scheduling) {
  stopping_.store(false);
  time_origin_ns_ = time_origin_ns;
  receiver_ = std::thread([this] { receive_loop(); });
  std::promise<SenderSetup> setup_promise;
  auto setup = setup_promise.get_future();
  // The sender sends what is published after this call, however late its thread first runs.
  const runtime::SampleRing& last_ring = *rings_.back();
  const SendFrom from{last_ring.epoch(), last_ring.newest()};
  sender_ = std::thread([this, time_origin_ns, scheduling, from, &setup_promise] {
    SenderSetup granted;
    if (scheduling.cpu >= 0) granted.cpu_error = runtime::pin_to_cpu(scheduling.cpu);
    if (scheduling.priority > 0) granted.priority_error = runtime::set_fifo_priority(scheduling.priority);
    setup_promise.set_value(granted);
    send_loop(time_origin_ns, from);
  });
  return setup.get();
}

void UdpEndpoint::stop() {
  stopping_.store(true);
  for (runtime::SampleRing* ring : rings_) ring->stop();  // wakes the sender
  if (receiver_.joinable()) receiver_.join();
  if (sender_.joinable()) sender_.join();
}

void UdpEndpoint::receive_loop() {
  std::array<std::uint8_t, 2048> buffer{};
  while (!stopping_.load(std::memory_order_acquire)) {
    pollfd pfd{socket_, POLLIN, 0};
    if (::poll(&pfd, 1, 50) <= 0) continue;  // 50 ms: how fast stop() is noticed
    UdpAddress from;
    from.length = sizeof(from.storage);
    const ssize_t n = ::recvfrom(socket_, buffer.data(), buffer.size(), 0,
                                 reinterpret_cast<sockaddr*>(&from.storage), &from.length);
    if (n < 0) continue;
    const std::span<const std::uint8_t> datagram(buffer.data(), static_cast<std::size_t>(n));
    wire::Header header;
    std::optional<wire::Key> key;
    bool accepted = wire::peek_header(datagram, header) == wire::DecodeError::kNone &&
                    (key = sessions_.key_of(header.session_id)).has_value();
    if (accepted) {
      switch (header.type) {
        case wire::DatagramType::kHeartbeat:
          accepted = handle_heartbeat(datagram, header, *key, from);
          break;
        case wire::DatagramType::kPathResponse:
          accepted = handle_path_response(datagram, header, *key, from);
          break;
        default:  // State and PathChallenge go the other way
          accepted = false;
      }
    }
    (accepted ? counters_.received : counters_.dropped).fetch_add(1, std::memory_order_relaxed);
  }
}

bool UdpEndpoint::handle_heartbeat(std::span<const std::uint8_t> datagram,
                                   const wire::Header& peeked, const wire::Key& key,
                                   const UdpAddress& from) {
  wire::Header header;
  wire::HeartbeatPayload heartbeat;
  if (wire::decode_heartbeat(datagram, key, header, heartbeat) != wire::DecodeError::kNone) {
    return false;
  }
  using Verdict = HeartbeatOutcome::Verdict;
  HeartbeatReport report{heartbeat.last_state_sequence, heartbeat.states_received,
                         heartbeat.states_lost, std::nullopt};
  if (time_origin_ns_ && heartbeat.last_state_sequence > 0) {
    // Server time now, less the echoed tick stamp, less the time the client held it. A client can
    // only misreport its own figures; nonsense (negative, over a minute) is not kept.
    // (Checked arithmetic: the echo is the client's to choose, extremes included.)
    constexpr std::int64_t kMaxRoundTripNs = 60'000'000'000;
    const std::int64_t server_now = runtime::monotonic_now_ns() - *time_origin_ns_;
    std::int64_t round_trip = 0;
    const bool overflow =
        __builtin_sub_overflow(server_now, heartbeat.echo_state_time_ns, &round_trip) ||
        __builtin_sub_overflow(round_trip, heartbeat.echo_hold_ns, &round_trip);
    if (!overflow && heartbeat.echo_hold_ns >= 0 && round_trip >= 0 &&
        round_trip <= kMaxRoundTripNs) {
      report.round_trip_ns = round_trip;
    }
  }
  const HeartbeatOutcome outcome =
      sessions_.on_heartbeat(peeked.session_id, header.sequence, from, SteadyClock::now(), report);
  if (outcome.verdict == Verdict::kAccepted || outcome.verdict == Verdict::kChallenge) {
    if (heartbeat.last_state_sequence > 0) acknowledgement_arrived();
  }
  switch (outcome.verdict) {
    case Verdict::kAccepted:
      return true;
    case Verdict::kChallenge: {
      std::array<std::uint8_t, wire::kPathDatagramSize> bytes{};
      wire::Header reply;
      reply.session_id = header.session_id;
      reply.sequence = header.sequence;
      wire::encode_path_challenge(reply, {outcome.nonce, header.sequence}, key, bytes);
      if (::sendto(socket_, bytes.data(), bytes.size(), MSG_DONTWAIT,
                   reinterpret_cast<const sockaddr*>(&from.storage), from.length) >= 0) {
        counters_.challenges_sent.fetch_add(1, std::memory_order_relaxed);
      }
      return true;
    }
    case Verdict::kRateLimited:
      counters_.rate_limited.fetch_add(1, std::memory_order_relaxed);
      return false;
    case Verdict::kForeignSource:
      counters_.foreign_source.fetch_add(1, std::memory_order_relaxed);
      return false;
    case Verdict::kStale:
      return false;
  }
  return false;
}

bool UdpEndpoint::handle_path_response(std::span<const std::uint8_t> datagram,
                                       const wire::Header& peeked, const wire::Key& key,
                                       const UdpAddress& from) {
  wire::Header header;
  wire::PathResponsePayload response;
  return wire::decode_path_response(datagram, key, header, response) == wire::DecodeError::kNone &&
         sessions_.on_path_response(peeked.session_id, header.sequence, response.nonce, from);
}

void plan_sends(std::span<const Subscriber> subscribers, std::uint64_t last_tick,
                std::uint64_t newest, bool conflate, std::vector<PlannedSend>& out,
                std::uint64_t& skipped) {
  out.clear();
  for (std::size_t i = 0; i < subscribers.size(); ++i) {
    const Subscriber& subscriber = subscribers[i];
    if (!conflate) continue;
    // Conflating, a subscriber gets only its newest due tick; the due ones before it are skipped
    // (counted here, and numbered with the one sent).
    const std::uint64_t from = std::max(last_tick + 1, subscriber.first_tick);
    if (newest < from) continue;
    const std::uint64_t first_due = (from + subscriber.decimation - 1) / subscriber.decimation;
    const std::uint64_t last_due = newest / subscriber.decimation;
    if (last_due > first_due) skipped += last_due - first_due;
  }
  for (std::uint64_t tick = last_tick + 1; tick <= newest; ++tick) {
    for (std::size_t i = 0; i < subscribers.size(); ++i) {
      const Subscriber& subscriber = subscribers[i];
      if (tick % subscriber.decimation != 0 || tick < subscriber.first_tick) continue;
      if (conflate && tick + subscriber.decimation <= newest) continue;  // a newer one is due
      std::uint64_t skipped_before = 0;
      if (conflate) {
        const std::uint64_t from = std::max(last_tick + 1, subscriber.first_tick);
        skipped_before = tick / subscriber.decimation - (from + subscriber.decimation - 1) / subscriber.decimation;
      }
      out.push_back({i, tick, skipped_before});
    }
  }
}

std::uint64_t flow_limit(const Subscriber& subscriber, std::uint64_t sequenced,
                         std::uint64_t acknowledged, std::uint64_t last_tick) {
  if (subscriber.ack_window == 0) return ~std::uint64_t{0};
  const std::uint64_t outstanding = sequenced > acknowledged ? sequenced - acknowledged : 0;
  const std::uint64_t credit = subscriber.ack_window > outstanding ? subscriber.ack_window - outstanding : 0;
  // Its next due tick after last_tick; `credit` due ticks from there may go, and the ticks up to
  // (not including) the one after them.
  const std::uint64_t d = subscriber.decimation;
  const std::uint64_t from = std::max(last_tick + 1, subscriber.first_tick);
  const std::uint64_t next_due = (from + d - 1) / d * d;
  return next_due + credit * d - 1;
}

void UdpEndpoint::acknowledgement_arrived() {
  {
    std::lock_guard lock(acknowledgement_mutex_);
    ++acknowledgements_;
  }
  acknowledgement_cv_.notify_all();
}

namespace {

/// One datagram of a wake-up, encoded and waiting for sendmmsg with the others.
struct Outgoing {
  std::array<std::uint8_t, wire::kMaxDatagramSize> bytes;
  iovec iov;
  const Subscriber* subscriber;
  std::int64_t stamp_ns;  // the tick's time stamp (server time)
};

/// Lockstep flow control over the sender's wake-ups: how far the flow-controlled subscribers'
/// windows let a round go, and which subscriber has stalled (nothing acknowledged for
/// kAckStallTimeout while its window was full), to be sent on without waiting until it catches up.
class FlowControl {
 public:
  /// Room for `capacity` subscribers, so that a change of subscribers up to it allocates nothing.
  explicit FlowControl(std::size_t capacity) {
    waiting_since_.reserve(capacity);
    unpaced_.reserve(capacity);
    acknowledged_at_stall_.reserve(capacity);
  }

  /// The subscribers changed: every one starts paced, waiting for nothing.
  void reset(std::size_t subscribers) {
    waiting_since_.assign(subscribers, std::nullopt);
    unpaced_.assign(subscribers, false);
    acknowledged_at_stall_.assign(subscribers, 0);
  }

  /// The newest tick, at most `published`, that this round may send without a paced subscriber's
  /// unacknowledged sequence numbers passing its window; a stall found is counted in `stalls`.
  std::uint64_t newest(std::span<const Subscriber> subscribers, std::uint64_t published, std::uint64_t last_tick,
                       std::atomic<std::uint64_t>& stalls) {
    std::uint64_t newest = published;
    const auto now = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < subscribers.size(); ++i) {
      const Subscriber& subscriber = subscribers[i];
      if (subscriber.ack_window == 0) continue;
      const std::uint64_t sequenced = subscriber.sequenced->load(std::memory_order_relaxed);
      const std::uint64_t acknowledged = subscriber.acknowledged->load(std::memory_order_acquire);
      const std::uint64_t limit = flow_limit(subscriber, sequenced, acknowledged, last_tick);
      if (unpaced_[i]) {
        // Sent on without waiting since it stalled; paced again once it acknowledges again
        // and has caught up to within its window.
        if (acknowledged > acknowledged_at_stall_[i] && sequenced <= acknowledged + subscriber.ack_window) {
          unpaced_[i] = false;
        }
        continue;
      }
      if (limit >= published) {
        waiting_since_[i].reset();
        continue;
      }
      if (!waiting_since_[i]) waiting_since_[i] = now;
      if (now - *waiting_since_[i] >= kAckStallTimeout) {
        unpaced_[i] = true;
        acknowledged_at_stall_[i] = acknowledged;
        waiting_since_[i].reset();
        stalls.fetch_add(1, std::memory_order_relaxed);
        continue;
      }
      newest = std::min(newest, limit);
    }
    return newest;
  }

 private:
  // Per subscriber (by index): since when its full window has held the sender up, whether it is
  // being sent on without waiting, and what it had acknowledged when it stalled.
  std::vector<std::optional<std::chrono::steady_clock::time_point>> waiting_since_;
  std::vector<bool> unpaced_;
  std::vector<std::uint64_t> acknowledged_at_stall_;
};

/// Encodes the planned sends into `outgoing` (grown as needed): each tick's samples read once from
/// `rings`, each due sample numbered in its subscriber's sequence whether it is sent or not (a
/// sample the ring no longer holds is missed, counted). Returns how many datagrams it encoded.
std::size_t encode_plan(std::span<const PlannedSend> plan, std::span<const Subscriber> subscribers,
                        std::span<runtime::SampleRing* const> rings, std::vector<runtime::TickSample>& samples,
                        std::vector<bool>& present, std::vector<Outgoing>& outgoing, UdpCounters& counters) {
  if (outgoing.size() < plan.size()) outgoing.resize(plan.size());
  std::size_t count = 0;
  std::uint64_t read_tick = 0;  // the tick whose samples are in `samples`
  for (const PlannedSend& send : plan) {
    const Subscriber& subscriber = subscribers[send.subscriber];
    if (subscriber.device_index >= rings.size()) continue;
    if (send.tick != read_tick) {  // each tick's samples read once, for whoever is sent them
      for (std::size_t port = 0; port < rings.size(); ++port) present[port] = rings[port]->read(send.tick, samples[port]);
      read_tick = send.tick;
    }
    const std::uint64_t sequence = subscriber.sequenced->load(std::memory_order_relaxed) + send.skipped_before + 1;
    subscriber.sequenced->store(sequence, std::memory_order_release);
    const bool missed = !present[subscriber.device_index];
    if (const std::uint64_t unsent = send.skipped_before + (missed ? 1 : 0); unsent > 0 && subscriber.unsent) {
      subscriber.unsent->fetch_add(unsent, std::memory_order_relaxed);
    }
    if (missed) {
      counters.samples_missed.fetch_add(1, std::memory_order_relaxed);
      continue;
    }
    const runtime::TickSample& sample = samples[subscriber.device_index];
    wire::Header header;
    header.session_id = subscriber.session_id;
    header.sequence = sequence;
    header.time_ns = sample.time_ns;
    Outgoing& out = outgoing[count++];
    const std::size_t size = wire::encode_state(header, state_payload(sample), subscriber.key, out.bytes);
    out.iov = {out.bytes.data(), size};
    out.subscriber = &subscriber;
    out.stamp_ns = sample.time_ns;
  }
  return count;
}

/// Hands the first `count` of `outgoing` to the kernel (sendmmsg, in batches of UIO_MAXIOV). Each
/// client's count goes up before its datagram leaves (and down again if it could not): a client
/// that reports what it received (its heartbeat) never reports more than was sent. A datagram the
/// kernel refused (its socket buffer full, an unreachable address) is counted and the rest go on.
/// Returns when (CLOCK_MONOTONIC, ns) the first was handed over where `stamp`, else 0.
std::int64_t send_batch(int socket, std::span<const Outgoing> outgoing, std::size_t count,
                        std::vector<mmsghdr>& messages, UdpCounters& counters, bool stamp) {
  messages.assign(count, mmsghdr{});
  for (std::size_t i = 0; i < count; ++i) {
    msghdr& m = messages[i].msg_hdr;
    m.msg_name = const_cast<sockaddr_storage*>(&outgoing[i].subscriber->address.storage);
    m.msg_namelen = outgoing[i].subscriber->address.length;
    m.msg_iov = const_cast<iovec*>(&outgoing[i].iov);
    m.msg_iovlen = 1;
  }
  for (std::size_t i = 0; i < count; ++i) {
    if (const auto& per_client = outgoing[i].subscriber->sent) per_client->fetch_add(1, std::memory_order_relaxed);
  }
  const std::int64_t handed_ns = stamp ? runtime::monotonic_now_ns() : 0;
  for (std::size_t first = 0; first < count;) {
    const unsigned chunk = static_cast<unsigned>(std::min<std::size_t>(count - first, UIO_MAXIOV));
    const int sent = ::sendmmsg(socket, messages.data() + first, chunk, MSG_DONTWAIT);
    const std::size_t done = sent > 0 ? static_cast<std::size_t>(sent) : 0;
    counters.sent.fetch_add(done, std::memory_order_relaxed);
    first += done;
    if (done < chunk) {
      counters.send_errors.fetch_add(1, std::memory_order_relaxed);
      if (const auto& per_client = outgoing[first].subscriber->sent) {
        per_client->fetch_sub(1, std::memory_order_relaxed);
      }
      if (const auto& unsent = outgoing[first].subscriber->unsent) unsent->fetch_add(1, std::memory_order_relaxed);
      ++first;
    }
  }
  return handed_ns;
}

}  // namespace

void UdpEndpoint::send_loop(std::optional<std::int64_t> time_origin_ns, SendFrom from) {
  // Real time conflates: when this thread has fallen behind (the host was busy), each subscriber
  // gets only its newest due sample and the older ones are skipped and counted, never queued —
  // for haptics and graphics a stale sample is worse than a lost one. Lockstep sends every due
  // tick (time there is the client's to step; nothing goes stale), and holds a flow-controlled
  // subscriber's ticks back while its window of unacknowledged datagrams is full.
  // Every due sample takes its subscriber's next sequence number, whether it is sent, skipped or
  // missed: a client sees each one it did not get as a gap.
  const bool conflate = time_origin_ns.has_value();
  std::vector<Subscriber> subscribers;
  subscribers.reserve(sessions_.max_sessions());  // refilled in place as sessions come and go
  std::uint64_t subscribers_version = ~0ull;
  FlowControl flow(sessions_.max_sessions());
  std::vector<PlannedSend> plan;
  // The loop publishes the ports in order, the last port last: once its ring holds a tick, every
  // port's ring does.
  const runtime::SampleRing& last_ring = *rings_.back();
  std::uint32_t epoch = from.epoch;
  std::uint64_t last_tick = from.tick;
  std::vector<runtime::TickSample> samples(rings_.size());  // one tick's, per port
  std::vector<bool> present(rings_.size());
  // A wake-up's datagrams, encoded first and handed to the kernel together (sendmmsg): one
  // system call per batch instead of one per subscriber.
  std::vector<Outgoing> outgoing;
  std::vector<mmsghdr> messages;
  while (!last_ring.stopping()) {
    last_ring.wait_beyond(last_tick, epoch);
    if (last_ring.stopping()) break;
    if (const std::uint32_t now = last_ring.epoch(); now != epoch) {
      // A lockstep reset: the ticks start again from 1 (the sequences go on).
      epoch = now;
      last_tick = 0;
      sent_through_.store(0, std::memory_order_release);
      continue;
    }
    const std::uint64_t published = last_ring.newest();
    if (const auto version = sessions_.subscribers_version(); version != subscribers_version) {
      sessions_.subscribers(subscribers);
      subscribers_version = version;
      flow.reset(subscribers.size());
    }
    // How far the flow-controlled subscribers' windows let this round go (lockstep only: the
    // real-time sender takes no lock here).
    std::uint64_t acknowledgements_seen = 0;
    std::uint64_t newest = published;
    if (!conflate) {
      {
        std::lock_guard lock(acknowledgement_mutex_);
        acknowledgements_seen = acknowledgements_;
      }
      newest = flow.newest(subscribers, published, last_tick, counters_.ack_stalls);
    }
    if (newest <= last_tick) {
      // Every window that matters is full: wait for an acknowledgement (or the stall deadline;
      // a short bound, so a stop, a reset or a subscriber leaving is seen soon too).
      std::unique_lock lock(acknowledgement_mutex_);
      acknowledgement_cv_.wait_for(lock, std::chrono::milliseconds(10),
                                   [&] { return acknowledgements_ != acknowledgements_seen; });
      continue;
    }
    std::uint64_t skipped = 0;
    plan_sends(subscribers, last_tick, newest, conflate, plan, skipped);
    counters_.samples_skipped.fetch_add(skipped, std::memory_order_relaxed);
    const std::size_t count = encode_plan(plan, subscribers, rings_, samples, present, outgoing, counters_);
    const std::int64_t handed_ns = send_batch(socket_, outgoing, count, messages, counters_, time_origin_ns.has_value());
    if (time_origin_ns && count > 0) {
      // The tick's datagrams were handed to the kernel at handed_ns; the first left then.
      counters_.send_delay.record(handed_ns - (*time_origin_ns + outgoing[0].stamp_ns), handed_ns);
    }
    last_tick = newest;
    sent_through_.store(newest, std::memory_order_release);
  }
}

bool UdpEndpoint::wait_sent_through(std::uint64_t tick, std::chrono::milliseconds timeout) const {
  const auto give_up = std::chrono::steady_clock::now() + timeout;
  while (sent_through_.load(std::memory_order_acquire) < tick) {
    if (std::chrono::steady_clock::now() > give_up || stopping_.load()) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(100));
  }
  return true;
}

}  // namespace haptic::net
