#include "udp_link.hpp"

#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <future>

#include "haptic/error.hpp"

namespace haptic::detail {
namespace {

std::int64_t steady_ns(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
}

Vec3 to_vec(const wire::Vec3d& v) { return {v.x, v.y, v.z}; }

// The socket's receive buffer (the kernel doubles it). Unit: B.
constexpr int kReceiveBufferBytes = 1 << 20;
// At most this many datagrams are taken in one wake-up before the newest is handed out.
constexpr int kMaxDrain = 1024;

/// CLOCK_REALTIME − CLOCK_MONOTONIC now: the kernel stamps arrivals on the former
/// (SO_TIMESTAMPNS), steady_clock is the latter.
std::int64_t realtime_minus_monotonic_ns() {
  timespec a{}, r{}, b{};
  clock_gettime(CLOCK_MONOTONIC, &a);
  clock_gettime(CLOCK_REALTIME, &r);
  clock_gettime(CLOCK_MONOTONIC, &b);
  const auto ns = [](const timespec& t) {
    return static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
  };
  return ns(r) - (ns(a) + ns(b)) / 2;
}

}  // namespace

UdpLink::UdpLink(const std::string& host, std::uint16_t port, std::uint64_t session_id,
                 const wire::Key& key, std::chrono::milliseconds heartbeat_period)
    : heartbeat_timer_(io_),
      heartbeat_period_(heartbeat_period),
      session_id_(session_id),
      key_(key) {
  asio::error_code error;
  asio::ip::udp::resolver resolver(io_);
  const auto results = resolver.resolve(host, std::to_string(port), error);
  if (error || results.empty()) {
    throw ConnectionError("UDP: cannot resolve " + host + ": " + error.message());
  }
  // Prefer IPv4: hapticd binds its data plane to 0.0.0.0 by default, and "localhost" often
  // resolves to ::1 first, where no one would answer our heartbeats.
  server_ = *results.begin();
  for (const auto& entry : results) {
    if (entry.endpoint().address().is_v4()) {
      server_ = entry.endpoint();
      break;
    }
  }
  socket_ = ::socket(server_.protocol().family(), SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (socket_ < 0) throw ConnectionError(std::string("UDP: cannot open a socket: ") + std::strerror(errno));
  const asio::ip::udp::endpoint any(server_.protocol(), 0);
  if (::bind(socket_, any.data(), static_cast<socklen_t>(any.size())) != 0) {
    const std::string why = std::strerror(errno);
    ::close(socket_);
    throw ConnectionError("UDP: cannot bind a socket: " + why);
  }
  // Room for a lockstep Step's burst (another client's Step of many ticks sends them all at once;
  // the tail of a burst that overflows is what is lost, and it holds the newest tick). What waits
  // here does not go stale on its way to the application: each wake-up drains the socket and
  // hands out only the newest sample. (Handing out every queued datagram in order is what once
  // made samples a second old.) The kernel may cap the size at net.core.rmem_max.
  ::setsockopt(socket_, SOL_SOCKET, SO_RCVBUF, &kReceiveBufferBytes, sizeof kReceiveBufferBytes);
  // The kernel's receive stamp on each datagram: State::arrived_at.
  const int on = 1;
  ::setsockopt(socket_, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on);
  wake_fd_ = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (wake_fd_ < 0) {
    const std::string why = std::strerror(errno);
    ::close(socket_);
    throw ConnectionError("UDP: cannot make an eventfd: " + why);
  }

  send_heartbeat();  // at once, so the server learns where to send state
  schedule_heartbeat();
  thread_ = std::thread([this] { io_.run(); });
  receiver_ = std::thread([this] { receive_loop(); });
}

UdpLink::~UdpLink() {
  stopping_.store(true);
  const std::uint64_t one = 1;
  (void)!::write(wake_fd_, &one, sizeof one);
  if (receiver_.joinable()) receiver_.join();
  io_.stop();
  if (thread_.joinable()) thread_.join();
  ::close(wake_fd_);
  ::close(socket_);
}

void UdpLink::receive_loop() {
  while (!stopping_.load()) {
    pollfd fds[2] = {{socket_, POLLIN, 0}, {wake_fd_, POLLIN, 0}};
    if (::poll(fds, 2, -1) < 0 && errno != EINTR) break;
    if (stopping_.load()) break;
    if ((fds[0].revents & POLLIN) != 0) {
      std::lock_guard lock(receive_mutex_);
      Batch batch;
      batch.received_at = std::chrono::steady_clock::now();
      drain(batch);
      hand_out(batch);
    }
    acknowledge_if_due();
    deliver();
  }
}

std::uint32_t UdpLink::ack_window_capacity() const {
  int granted = 0;
  socklen_t length = sizeof granted;
  if (::getsockopt(socket_, SOL_SOCKET, SO_RCVBUF, &granted, &length) != 0) granted = 0;
  // The kernel charges a datagram its buffer's true size (about 1 KiB on loopback for a State);
  // 2 KiB each leaves room for what else queues (challenges) and for larger buffers' overhead.
  constexpr std::uint32_t kBytesPerDatagram = 2048;
  return std::clamp<std::uint32_t>(static_cast<std::uint32_t>(std::max(granted, 0)) / kBytesPerDatagram,
                                   16, 65536);
}

void UdpLink::acknowledge_if_due() {
  const std::uint32_t window = ack_window_.load(std::memory_order_relaxed);
  if (window == 0) return;
  bool due = false;
  {
    std::lock_guard lock(mutex_);
    // Taken before the callback runs: the server may send on while the application works, up to
    // what the socket holds. (Observers, the recorder among them, have seen these already.)
    if (counters_.accepted - accepted_at_acknowledgement_ >= std::max<std::uint32_t>(1, window / 4)) {
      accepted_at_acknowledgement_ = counters_.accepted;
      due = true;
    }
  }
  if (due) send_heartbeat();  // its last_state_sequence is the acknowledgement
}

void UdpLink::send_to_server(std::span<const std::uint8_t> bytes) {
  asio::ip::udp::endpoint to;
  {
    std::lock_guard lock(identity_mutex_);
    to = server_;
  }
  // A lost datagram is made good by the next heartbeat (or, for an answer, the next challenge).
  (void)::sendto(socket_, bytes.data(), bytes.size(), MSG_DONTWAIT, to.data(),
                 static_cast<socklen_t>(to.size()));
}

void UdpLink::deliver() {
  for (;;) {  // again if the callback's own calls read a newer State meanwhile
    std::optional<State> state;
    {
      std::lock_guard lock(receive_mutex_);
      state.swap(pending_);
    }
    if (!state) return;
    std::lock_guard lock(callback_mutex_);
    if (!callback_) return;
    callback_started_ns_.store(steady_ns(std::chrono::steady_clock::now()), std::memory_order_relaxed);
    in_callback_.store(true, std::memory_order_release);
    callback_(*state);
    in_callback_.store(false, std::memory_order_release);
    callback_ended_ns_.store(steady_ns(std::chrono::steady_clock::now()), std::memory_order_relaxed);
  }
}

void UdpLink::send_heartbeat() {
  if (!heartbeats_enabled_.load()) return;
  std::array<std::uint8_t, wire::kHeartbeatDatagramSize> bytes{};
  wire::Header header;
  wire::Key key;
  {
    std::lock_guard lock(identity_mutex_);
    header.session_id = session_id_;
    key = key_;
  }
  header.sequence = ++heartbeat_sequence_;
  header.time_ns = steady_ns(std::chrono::steady_clock::now());
  wire::HeartbeatPayload payload;
  payload.client_time_ns = header.time_ns;
  {
    std::lock_guard lock(mutex_);
    payload.last_state_sequence = last_sequence_;
    // What this session's stream brought, and the newest State's stamp with how long it was held
    // here: the server reads the round trip from it (GetStats).
    payload.states_received = counters_.accepted - session_accepted_base_;
    payload.states_lost =
        counters_.lost > session_lost_base_ ? counters_.lost - session_lost_base_ : 0;
    if (last_sequence_ > 0) {
      payload.echo_state_time_ns = echo_state_time_ns_;
      payload.echo_hold_ns = std::max<std::int64_t>(
          0, header.time_ns - steady_ns(echo_received_at_));
    }
  }
  wire::encode_heartbeat(header, payload, key, bytes);
  send_to_server(bytes);
}

void UdpLink::schedule_heartbeat() {
  heartbeat_timer_.expires_after(heartbeat_period_);
  heartbeat_timer_.async_wait([this](const asio::error_code& error) {
    if (error) return;
    send_heartbeat();
    schedule_heartbeat();
  });
}

void UdpLink::drain(Batch& batch) {
  // The link's own buffers: drain runs only under receive_mutex_.
  auto& slots = receive_buffers_->slots;
  auto& messages = receive_buffers_->messages;
  const std::int64_t realtime_offset = realtime_minus_monotonic_ns();
  for (int read = 0; read < kMaxDrain;) {
    for (unsigned i = 0; i < kBatch; ++i) {
      slots[i].iov = {slots[i].bytes.data(), slots[i].bytes.size()};
      messages[i] = {};
      messages[i].msg_hdr.msg_iov = &slots[i].iov;
      messages[i].msg_hdr.msg_iovlen = 1;
      messages[i].msg_hdr.msg_control = slots[i].control.data();
      messages[i].msg_hdr.msg_controllen = slots[i].control.size();
    }
    const int got = ::recvmmsg(socket_, messages.data(), kBatch, MSG_DONTWAIT, nullptr);
    if (got <= 0) break;
    for (int i = 0; i < got; ++i) {
      std::optional<std::chrono::steady_clock::time_point> arrived_at;
      msghdr& header = messages[static_cast<std::size_t>(i)].msg_hdr;
      for (cmsghdr* c = CMSG_FIRSTHDR(&header); c != nullptr; c = CMSG_NXTHDR(&header, c)) {
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
          timespec ts{};
          std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
          const std::int64_t ns =
              static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec - realtime_offset;
          arrived_at = std::chrono::steady_clock::time_point(std::chrono::nanoseconds(ns));
        }
      }
      take({slots[static_cast<std::size_t>(i)].bytes.data(), messages[static_cast<std::size_t>(i)].msg_len},
           arrived_at, batch);
    }
    read += got;
    if (static_cast<unsigned>(got) < kBatch) break;
  }
}

void UdpLink::hand_out(const Batch& batch) {
  if (!batch.newest) return;
  {
    std::lock_guard lock(mutex_);
    // The States passed over for the newest: those that queued behind a running callback, and
    // those that arrived together otherwise.
    const std::uint64_t passed_over = batch.accepted - 1;
    const std::uint64_t behind_callback = std::min(passed_over, batch.during_callback);
    counters_.callback_skipped += behind_callback;
    counters_.skipped += passed_over - behind_callback;
    // Older than what we have (reordered on the way): counted, but the newest stays latest.
    if (!have_latest_ || batch.newest->tick >= latest_.tick) {
      latest_ = *batch.newest;
      have_latest_ = true;
    }
  }
  arrived_.notify_all();
  if (!has_callback_.load(std::memory_order_acquire)) return;
  if (pending_ && pending_->tick <= batch.newest->tick) {
    std::lock_guard lock(mutex_);
    // Replaced before the callback saw it: while it runs (a call of its own read the socket), or
    // by a second read in the same wake-up.
    ++(in_callback_.load(std::memory_order_acquire) ? counters_.callback_skipped : counters_.skipped);
  }
  if (!pending_ || pending_->tick <= batch.newest->tick) pending_ = *batch.newest;
}

void UdpLink::answer_challenge(std::span<const std::uint8_t> datagram) {
  wire::Header header;
  wire::PathChallengePayload challenge;
  wire::Key key;
  std::uint64_t session_id = 0;
  {
    std::lock_guard lock(identity_mutex_);
    key = key_;
    session_id = session_id_;
  }
  if (wire::decode_path_challenge(datagram, key, header, challenge) != wire::DecodeError::kNone ||
      header.session_id != session_id) {
    std::lock_guard lock(mutex_);
    ++counters_.rejected;
    return;
  }
  if (!heartbeats_enabled_.load()) return;  // a lost client answers nothing
  // From this socket, so that the address the server saw is the one proven to receive.
  std::array<std::uint8_t, wire::kPathDatagramSize> bytes{};
  wire::Header reply;
  reply.session_id = session_id;
  reply.sequence = ++heartbeat_sequence_;
  reply.time_ns = steady_ns(std::chrono::steady_clock::now());
  wire::encode_path_response(reply, {challenge.nonce, reply.time_ns}, key, bytes);
  send_to_server(bytes);  // lost: the next heartbeat draws another challenge
  std::lock_guard lock(mutex_);
  ++counters_.challenges_answered;
  last_heard_ = std::chrono::steady_clock::now();
}

void UdpLink::take(std::span<const std::uint8_t> datagram,
                   std::optional<std::chrono::steady_clock::time_point> arrived_at, Batch& batch) {
  std::optional<State>& newest = batch.newest;
  wire::Header header;
  if (wire::peek_header(datagram, header) == wire::DecodeError::kNone &&
      header.type == wire::DatagramType::kPathChallenge) {
    answer_challenge(datagram);
    return;
  }
  wire::StatePayload payload;
  wire::Key key;
  std::uint64_t session_id = 0;
  {
    std::lock_guard lock(identity_mutex_);
    key = key_;
    session_id = session_id_;
  }
  const bool ok = wire::decode_state(datagram, key, header, payload) == wire::DecodeError::kNone &&
                  header.session_id == session_id;
  std::lock_guard lock(mutex_);
  if (!ok) {
    ++counters_.rejected;
    return;
  }
  if (header.sequence <= stale_through_) {
    ++counters_.skipped;  // of a run before a lockstep reset
    return;
  }
  // The server numbers each subscription's States without gaps: a jump is datagrams lost on the
  // way, and one arriving late (an older tick too) was not lost after all. A datagram seen before
  // (the network duplicated it) is dropped. A lower sequence with a newer tick is a new
  // subscription, numbered from 1 again.
  if (header.sequence > last_sequence_) {
    if (payload.tick < newest_tick_) {
      // A newer datagram with an older tick: the server's ticks started again (a lockstep reset
      // another client made). What was numbered before this one belongs to the old run.
      forget_ticks_locked();
      stale_through_ = header.sequence - 1;
      newest.reset();
    }
    counters_.lost += header.sequence - last_sequence_ - 1;
    const std::uint64_t shift = header.sequence - last_sequence_;
    seen_window_ = (shift >= 64 ? 0 : seen_window_ << shift) | 1u;
    last_sequence_ = header.sequence;
  } else if (payload.tick > newest_tick_) {
    last_sequence_ = header.sequence;
    seen_window_ = 1;
  } else {
    const std::uint64_t behind = last_sequence_ - header.sequence;
    if (behind >= 64) {
      // Too old to tell a late arrival from a copy: kept out of the loss count either way.
      ++counters_.reordered;
      return;
    }
    const std::uint64_t bit = std::uint64_t{1} << behind;
    if ((seen_window_ & bit) != 0) {
      ++counters_.duplicates;
      return;
    }
    seen_window_ |= bit;
    if (counters_.lost > 0) --counters_.lost;
    ++counters_.reordered;
  }
  ++counters_.accepted;
  ++batch.accepted;
  if (arrived_at) {
    // It queued while the callback ran: it arrived after the last call began, and before that
    // call ended (or the call is still running, when read from another thread's restart).
    const std::int64_t at = steady_ns(*arrived_at);
    const std::int64_t began = callback_started_ns_.load(std::memory_order_relaxed);
    const std::int64_t ended = callback_ended_ns_.load(std::memory_order_relaxed);
    if (began > 0 && at >= began && (at <= ended || ended < began)) ++batch.during_callback;
  }
  echo_state_time_ns_ = header.time_ns;
  echo_received_at_ = batch.received_at;
  State state;
  state.tick = payload.tick;
  state.sequence = header.sequence;
  state.server_time = static_cast<double>(header.time_ns) * 1e-9;
  state.position = to_vec(payload.p_WT);
  state.velocity = to_vec(payload.v_WT);
  state.force = to_vec(payload.F_T_W);
  state.proxy = to_vec(payload.p_WP);
  state.contact_count = payload.contact_count;
  state.flags = payload.flags;
  state.buttons = payload.buttons;
  if (payload.has_orientation) {  // StateOriented: the orientation and the torque
    state.orientation = Quaternion{payload.R_WT.w, payload.R_WT.x, payload.R_WT.y, payload.R_WT.z};
    state.torque = to_vec(payload.tau_T_W);
  }
  state.received_at = batch.received_at;
  state.arrived_at = arrived_at;
  last_heard_ = batch.received_at;
  newest_tick_ = std::max(newest_tick_, payload.tick);
  // How much longer than the quickest recent sample this one took: time spent queued anywhere.
  state.age = std::chrono::nanoseconds(clock_.add(header.time_ns, steady_ns(batch.received_at)));
  if (!newest || state.tick >= newest->tick) newest = state;
  for (const auto& tap : taps_) tap.second->on_sample(state);
}

void UdpLink::forget_ticks_locked() {
  newest_tick_ = 0;
  have_latest_ = false;
  last_polled_tick_.reset();
  clock_ = ClockSync{};
}

void UdpLink::restart_ticks() {
  // What is in the socket now belongs to the old run (the server sent it before it replied):
  // take it as usual first. Under the receive lock, so the receive thread takes nothing of it
  // after the old run is forgotten; any thread may call this (a callback included: it runs on
  // the receive thread, which holds no lock while it runs).
  std::lock_guard lock(receive_mutex_);
  Batch batch;
  batch.received_at = std::chrono::steady_clock::now();
  drain(batch);
  hand_out(batch);
  std::lock_guard state(mutex_);
  stale_through_ = last_sequence_;
  forget_ticks_locked();
}

void UdpLink::new_subscription() {
  std::lock_guard lock(mutex_);
  stale_through_ = 0;  // a subscription started afresh numbers from 1 again
}

void UdpLink::rebind(std::uint16_t port, std::uint64_t session_id, const wire::Key& key) {
  {
    std::lock_guard lock(receive_mutex_);  // no datagram is half taken under the old identity
    {
      std::lock_guard identity(identity_mutex_);
      server_.port(port);
      session_id_ = session_id;
      key_ = key;
    }
    heartbeat_sequence_ = 0;
    std::lock_guard state(mutex_);
    // The new session's ticks, sequences and server clock start again from zero.
    last_sequence_ = 0;
    seen_window_ = 0;
    stale_through_ = 0;
    session_accepted_base_ = counters_.accepted;
    session_lost_base_ = counters_.lost;
    forget_ticks_locked();
  }
  send_heartbeat_soon();
}

std::optional<std::chrono::steady_clock::time_point> UdpLink::last_heard() const {
  std::lock_guard lock(mutex_);
  return last_heard_;
}

void UdpLink::count_lost(std::uint64_t samples) {
  std::lock_guard lock(mutex_);
  counters_.lost += samples;
}

void UdpLink::add_tap(std::uint64_t id, std::shared_ptr<ReceiveObserver> tap) {
  std::lock_guard lock(mutex_);
  taps_.emplace_back(id, std::move(tap));
}

void UdpLink::remove_tap(std::uint64_t id) {
  std::shared_ptr<ReceiveObserver> removed;  // released outside the lock
  std::lock_guard lock(mutex_);
  for (auto it = taps_.begin(); it != taps_.end(); ++it) {
    if (it->first == id) {
      removed = std::move(it->second);
      taps_.erase(it);
      break;
    }
  }
}

void UdpLink::on_state(std::function<void(const State&)> callback) {
  std::lock_guard lock(callback_mutex_);  // waits for a callback in progress to return
  has_callback_.store(static_cast<bool>(callback), std::memory_order_release);
  callback_ = std::move(callback);
}

void UdpLink::offer(const State& state) {
  {
    std::lock_guard lock(mutex_);
    if (have_latest_ && state.tick <= latest_.tick) return;
    latest_ = state;
    have_latest_ = true;
  }
  arrived_.notify_all();
}

namespace {
/// Waits on `arrived` for `ready` up to `timeout`; a timeout of zero only looks (a condition
/// variable's wait with a deadline already past still costs a futex call: about 80 µs here).
template <typename Ready>
bool wait_ready(std::condition_variable& arrived, std::unique_lock<std::mutex>& lock,
                std::chrono::milliseconds timeout, Ready ready) {
  if (timeout <= std::chrono::milliseconds::zero()) return ready();
  return arrived.wait_for(lock, timeout, ready);
}
}  // namespace

bool UdpLink::poll(State& out, std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  if (!wait_ready(arrived_, lock, timeout, [this] {
        return have_latest_ && (!last_polled_tick_ || latest_.tick > *last_polled_tick_);
      })) {
    return false;
  }
  out = latest_;
  last_polled_tick_ = latest_.tick;
  return true;
}

bool UdpLink::wait_for_tick(std::uint64_t tick, State& out, std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  if (!wait_ready(arrived_, lock, timeout, [&] { return have_latest_ && latest_.tick >= tick; })) {
    return false;
  }
  out = latest_;
  last_polled_tick_ = latest_.tick;
  return true;
}

std::optional<std::chrono::nanoseconds> UdpLink::clock_offset() const {
  std::lock_guard lock(mutex_);
  const std::optional<std::int64_t> offset = clock_.offset_ns();
  if (!offset) return std::nullopt;
  return std::chrono::nanoseconds(*offset);
}

std::optional<double> UdpLink::clock_drift() const {
  std::lock_guard lock(mutex_);
  return clock_.drift();
}

std::optional<double> UdpLink::server_time_at(std::chrono::steady_clock::time_point local) const {
  std::lock_guard lock(mutex_);
  const std::optional<std::int64_t> server = clock_.server_ns_at(steady_ns(local));
  if (!server) return std::nullopt;
  return static_cast<double>(*server) * 1e-9;
}

ReceiveCounters UdpLink::counters() const {
  std::lock_guard lock(mutex_);
  return counters_;
}

}  // namespace haptic::detail
