// A simulated LAN between an SDK client and a real-time hapticd (issue 11 item 6): delay, jitter,
// loss, duplication and reordering on the data plane, delay and a pulled cable on the control
// plane. What must hold: the client's counters account for every State the network dropped or
// duplicated; the force on the device stays bounded and never steps, whatever is lost; a lease
// that runs out ramps the session's items out, and the client comes back with them; a server
// restart is survived within 2 s. Each run prints its figures (rate, latency, loss, force).
//
// The impairment is done in user space (tests/support/*_relay.hpp), which works everywhere;
// scripts/lan-netem runs the same client against the kernel's netem between network namespaces
// where the kernel has it.

#include <gtest/gtest.h>
#include <sys/time.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <memory>
#include <mutex>
#include <ostream>
#include <thread>
#include <vector>

#include "haptic/client.hpp"
#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"
#include "support/tcp_delay_relay.hpp"
#include "support/udp_impairment_relay.hpp"

namespace haptic::test {
namespace {

using std::chrono::milliseconds;
using std::chrono::microseconds;
using std::chrono::steady_clock;

// The wall the remote client holds, and the hand pressing into it: stiff enough that a force cut
// would be a step of several newtons.
constexpr double kWallStiffness = 1000.0;  // N/m
constexpr double kWallDamping = 1.0;       // N·s/m
constexpr double kRampMs = 50.0;           // the server's removal_ramp_ms (its default)
// The largest change of force from one tick to the next that the scene itself makes: the tight
// grip (800 N/m, 2 kg) moves the tool at most ~0.1 m/s against the wall, k·v·dt ≈ 0.1 N; a wall
// ramping in over 50 ms with the tool 10 mm deep adds 10 N / 50. A removal or appearance without
// its ramp steps by the whole contact force (4 to 10 N here).
constexpr double kMaxForceStepPerTick = 1.0;  // N

std::string real_time_config(int lease_ms) {
  return R"({"time_mode": "REAL_TIME", "udp_address": "127.0.0.1", "status_period_s": 0,
    "real_time": {"use_fifo": false}, "lease_timeout_ms": )" +
         std::to_string(lease_ms) + R"(, "simulated_point_mass": {"initial_position": {"z": 0.02}}})";
}

/// A network profile, both ways alike.
struct Profile {
  const char* name;
  Impairment impairment;
};

void PrintTo(const Profile& profile, std::ostream* out) { *out << profile.name; }

const Profile kProfiles[] = {
    {"lan_1ms", {.delay = microseconds(1000), .jitter = microseconds(200)}},
    {"busy_5ms_5pct",
     {.delay = microseconds(5000), .jitter = microseconds(2000), .loss = 0.05, .duplicate = 0.01,
      .reorder = 0.02}},
    {"bad_20ms_30pct",
     {.delay = microseconds(20000), .jitter = microseconds(5000), .loss = 0.30, .duplicate = 0.05,
      .reorder = 0.05}},
};

/// Every State a client's callback is handed (the newest each time), and the events it sees.
class Recorder {
 public:
  void attach(Client& client) {
    client.on_state([this](const State& state) {
      std::lock_guard lock(mutex_);
      states_.push_back(state);
    });
  }
  void watch(Client& client) {
    client.on_event([this](const Event& event) {
      std::lock_guard lock(mutex_);
      events_.push_back(event);
    });
  }
  std::vector<State> states() const {
    std::lock_guard lock(mutex_);
    return states_;
  }
  std::vector<Event> events() const {
    std::lock_guard lock(mutex_);
    return events_;
  }
  void clear() {
    std::lock_guard lock(mutex_);
    states_.clear();
  }

 private:
  mutable std::mutex mutex_;
  std::vector<State> states_;
  std::vector<Event> events_;
};

double norm(const Vec3& v) { return std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }

/// What a stream of samples says about the force: the largest magnitude and the largest change
/// per tick between samples (a gap of n ticks allows n times the per-tick change).
struct ForceFigures {
  double max_force = 0.0;          // N
  double max_step_per_tick = 0.0;  // N
  bool all_finite = true;
};

ForceFigures force_figures(std::vector<State> states) {
  std::sort(states.begin(), states.end(), [](const State& a, const State& b) { return a.tick < b.tick; });
  ForceFigures figures;
  for (std::size_t i = 0; i < states.size(); ++i) {
    const Vec3& f = states[i].force;
    figures.all_finite = figures.all_finite && std::isfinite(f.x) && std::isfinite(f.y) && std::isfinite(f.z);
    figures.max_force = std::max(figures.max_force, norm(f));
    if (i == 0 || states[i].tick <= states[i - 1].tick) continue;
    const Vec3& g = states[i - 1].force;
    const double change = norm({f.x - g.x, f.y - g.y, f.z - g.z});
    figures.max_step_per_tick =
        std::max(figures.max_step_per_tick, change / static_cast<double>(states[i].tick - states[i - 1].tick));
  }
  return figures;
}

/// Percentile (0 ... 1) of `values`, sorted in place.
double percentile(std::vector<double>& values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  return values[static_cast<std::size_t>(p * static_cast<double>(values.size() - 1))];
}

/// The hand presses the tool 10 mm into the wall's side of z = 0 and holds it (about 4.4 N).
OperatorInput press_into_wall() {
  OperatorInput input = OperatorInput::follow({0, 0, -0.01}, 0.0, 0.0);
  input.grip = OperatorInput::Grip::kTight;
  return input;
}

/// The hand moves the tool in and out of the wall once a second (0 to about 9 N).
OperatorInput stroke_through_wall() {
  OperatorInput input = OperatorInput::follow({0, 0, -0.005}, 0.0, 0.0);
  input.grip = OperatorInput::Grip::kTight;
  input.path.shape = OperatorInput::Path::Shape::kSine;
  input.path.amplitude = {0, 0, 0.015};
  input.path.frequency_hz = 1.0;
  return input;
}

ClientConfig remote_config(const ServerProcess& server, const TcpDelayRelay& control,
                           const UdpImpairmentRelay& data, const char* name) {
  ClientConfig config = config_for(server, name);
  config.server_address = control.address();
  config.udp_address = data.address();
  config.heartbeat_period = milliseconds(100);  // the SDK's default: what a LAN client runs with
  return config;
}

TEST(LanRelay, DropsDuplicatesAndDelaysAsConfiguredAndCountsWhatItDid) {
  // A plain UDP socket stands in for the server.
  const int server = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(server, reinterpret_cast<sockaddr*>(&address), sizeof(address)), 0);
  socklen_t length = sizeof(address);
  ::getsockname(server, reinterpret_cast<sockaddr*>(&address), &length);
  const timeval timeout{0, 200000};
  ::setsockopt(server, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof(timeout));
  const Impairment impairment{.delay = microseconds(3000), .jitter = microseconds(1000), .loss = 0.2,
                              .duplicate = 0.1, .reorder = 0.0};
  UdpImpairmentRelay relay(ntohs(address.sin_port), impairment, {}, 7);

  const int client = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  to.sin_port = htons(relay.port());
  constexpr int kSent = 2000;
  std::vector<steady_clock::time_point> sent_at(kSent);
  std::atomic<int> sent{0};
  int received = 0;
  double shortest_ms = 1e9;
  std::thread reader([&] {  // reads as they come, so the stand-in's buffer never overflows
    int index = 0;
    while (::recv(server, &index, sizeof(index), 0) == static_cast<ssize_t>(sizeof(index))) {
      ++received;
      if (index < 0 || index >= sent.load()) continue;
      const double ms = std::chrono::duration<double, std::milli>(steady_clock::now() - sent_at[index]).count();
      shortest_ms = std::min(shortest_ms, ms);
    }
  });
  for (int i = 0; i < kSent; ++i) {
    sent_at[i] = steady_clock::now();
    sent.store(i + 1);
    ::sendto(client, &i, sizeof(i), 0, reinterpret_cast<const sockaddr*>(&to), sizeof(to));
    if (i % 50 == 49) std::this_thread::sleep_for(milliseconds(1));
  }
  reader.join();  // ends 200 ms after the last datagram
  const RelayCounters counters = relay.to_server_counters();
  EXPECT_EQ(counters.received, static_cast<std::uint64_t>(kSent));
  EXPECT_EQ(counters.delivered, counters.received - counters.dropped + counters.duplicated);
  EXPECT_EQ(static_cast<std::uint64_t>(received), counters.delivered);
  // Binomial(2000, 0.2): σ ≈ 18; ±4σ.
  EXPECT_NEAR(static_cast<double>(counters.dropped), 400.0, 72.0);
  EXPECT_NEAR(static_cast<double>(counters.duplicated), 160.0, 60.0);
  EXPECT_GE(shortest_ms, 2.0);  // delay − jitter
  ::close(client);
  ::close(server);
}

class LanProfile : public ::testing::TestWithParam<Profile> {};

TEST_P(LanProfile, TheClientAccountsForEveryStateAndTheForceNeverSteps) {
  const Profile& profile = GetParam();
  ServerProcess server(real_time_config(1000));
  ASSERT_TRUE(server.time_origin().has_value());
  TcpDelayRelay control(server.grpc_port(), profile.impairment.delay);
  UdpImpairmentRelay data(server.udp_port(), profile.impairment, profile.impairment, 11);

  // An observer beside the server sees every tick of the device's force.
  Recorder truth;  // before the client whose callbacks it takes, so it outlives them
  Client observer(config_for(server, "observer"));
  truth.attach(observer);
  truth.watch(observer);
  observer.set_operator(stroke_through_wall());

  Recorder seen;
  Client remote(remote_config(server, control, data, "remote"));
  seen.attach(remote);
  ObjectHandle wall = remote.add_wall({.normal = {0, 0, 1}, .impedance = {kWallStiffness, kWallDamping}});
  const auto start = steady_clock::now();
  std::this_thread::sleep_for(milliseconds(3000));
  remote.subscribe(0);  // the stream stops; what is on its way arrives
  const double seconds = std::chrono::duration<double>(steady_clock::now() - start).count();
  std::this_thread::sleep_for(milliseconds(150));

  const ReceiveCounters counters = remote.receive_counters();
  const RelayCounters network = data.to_client_counters();
  const std::vector<State> states = seen.states();
  ASSERT_FALSE(states.empty());
  // Every State the server sent arrived once or was dropped on the way, and the SDK tells which:
  // its lost count misses only drops after the last State to arrive.
  EXPECT_EQ(counters.accepted, network.states_received - network.states_dropped);
  EXPECT_EQ(counters.duplicates, network.states_duplicated);
  EXPECT_LE(counters.lost, network.states_dropped);
  EXPECT_GE(counters.lost + 3, network.states_dropped);
  EXPECT_EQ(counters.rejected, 0u);

  std::vector<double> latency_ms;
  for (const State& state : states) {
    const auto stamped = *server.time_origin() + std::chrono::nanoseconds(std::llround(state.server_time * 1e9));
    latency_ms.push_back(std::chrono::duration<double, std::milli>(state.received_at - stamped).count());
  }
  const double p50 = percentile(latency_ms, 0.5);
  const double p99 = percentile(latency_ms, 0.99);
  const double delay_ms = std::chrono::duration<double, std::milli>(profile.impairment.delay).count();
  const double jitter_ms = std::chrono::duration<double, std::milli>(profile.impairment.jitter).count();
  EXPECT_GE(p50, delay_ms - jitter_ms);  // the network's delay is in what the client sees

  // The session held on: no lease ran out, the wall is still there.
  for (const Event& event : truth.events()) {
    EXPECT_NE(event.kind, Event::Kind::kLeaseExpired) << event.message;
  }
  const ForceFigures device = force_figures(truth.states());
  const ForceFigures remote_view = force_figures(states);
  EXPECT_TRUE(device.all_finite);
  EXPECT_TRUE(remote_view.all_finite);
  EXPECT_GT(device.max_force, 3.0) << "the hand never pressed into the wall";
  EXPECT_LE(device.max_force, 20.0);  // the device's max_force
  EXPECT_LE(device.max_step_per_tick, kMaxForceStepPerTick);
  EXPECT_LE(remote_view.max_step_per_tick, kMaxForceStepPerTick);
  EXPECT_EQ(observer.stats().objects, 1u);

  const double received = static_cast<double>(counters.accepted);
  std::printf(
      "lan %-16s: %.0f States/s received (%.1f %% lost on the way, %llu lost counted, %llu "
      "duplicates, %llu reordered); latency p50 %.2f ms, p99 %.2f ms; force max %.2f N, largest "
      "change %.3f N/tick (device), %.3f N/tick (as received)\n",
      profile.name, received / seconds,
      100.0 * static_cast<double>(network.states_dropped) / static_cast<double>(network.states_received),
      static_cast<unsigned long long>(counters.lost), static_cast<unsigned long long>(counters.duplicates),
      static_cast<unsigned long long>(counters.reordered), p50, p99, device.max_force,
      device.max_step_per_tick, remote_view.max_step_per_tick);
}

std::string profile_name(const ::testing::TestParamInfo<Profile>& param) { return param.param.name; }
INSTANTIATE_TEST_SUITE_P(Profiles, LanProfile, ::testing::ValuesIn(kProfiles), profile_name);

TEST(Lan, APulledCableRampsTheForceOutAtLeaseExpiryAndTheClientComesBackWithItsWall) {
  constexpr int kLeaseMs = 600;
  ServerProcess server(real_time_config(kLeaseMs));
  const Impairment lan = kProfiles[0].impairment;
  TcpDelayRelay control(server.grpc_port(), lan.delay);
  UdpImpairmentRelay data(server.udp_port(), lan, lan, 13);

  Recorder truth;  // before the client whose callbacks it takes, so it outlives them
  Client observer(config_for(server, "observer"));
  truth.attach(observer);
  truth.watch(observer);
  observer.set_operator(press_into_wall());

  ConnectionLog log;
  Client remote(remote_config(server, control, data, "remote"));
  log.attach(remote);
  ObjectHandle wall = remote.add_wall({.normal = {0, 0, 1}, .impedance = {kWallStiffness, kWallDamping}});
  const std::uint64_t first_session = remote.session_id();
  std::this_thread::sleep_for(milliseconds(800));  // pressed in and settled
  State before;
  ASSERT_TRUE(observer.poll_state(before, milliseconds(500)));
  ASSERT_GT(norm(before.force), 3.0) << "the hand is not pressing into the wall";

  data.set_partitioned(true);
  control.set_partitioned(true);
  const auto lost = log.wait(1, milliseconds(3000));
  ASSERT_TRUE(lost);
  EXPECT_EQ(lost->first.state, ConnectionChange::State::kLost);
  std::this_thread::sleep_for(milliseconds(kLeaseMs + 400));  // the lease has run out meanwhile
  const auto reconnected_from = steady_clock::now();
  data.set_partitioned(false);
  control.set_partitioned(false);
  const auto resumed = log.wait(2, milliseconds(4000));
  ASSERT_TRUE(resumed);
  EXPECT_EQ(resumed->first.state, ConnectionChange::State::kResumed);
  EXPECT_TRUE(resumed->first.new_session);
  EXPECT_EQ(resumed->first.items_not_restored, 0u);
  EXPECT_NE(remote.session_id(), first_session);
  const double reconnect_ms =
      std::chrono::duration<double, std::milli>(resumed->second - reconnected_from).count();
  EXPECT_LT(reconnect_ms, 2000.0);
  std::this_thread::sleep_for(milliseconds(300));  // the wall ramps back in and pushes the tool out

  // The lease ran out once, for the first session; from that tick the force went to zero over
  // the removal ramp, with no step, and came back the same way.
  const std::vector<Event> events = truth.events();
  const auto expiry = std::find_if(events.begin(), events.end(), [&](const Event& e) {
    return e.kind == Event::Kind::kLeaseExpired && e.session_id == first_session;
  });
  ASSERT_NE(expiry, events.end());
  std::vector<State> states = truth.states();
  std::sort(states.begin(), states.end(), [](const State& a, const State& b) { return a.tick < b.tick; });
  // The loop skips the periods an overrun lost, so ticks are found by their time stamps: the
  // first sample stamped at or after the expiry, and the first zero force from there.
  const auto at_expiry = std::find_if(states.begin(), states.end(), [&](const State& s) {
    return s.server_time >= expiry->server_time;
  });
  ASSERT_NE(at_expiry, states.end());
  const auto zero = std::find_if(at_expiry, states.end(), [&](const State& s) { return norm(s.force) == 0.0; });
  ASSERT_NE(zero, states.end()) << "the force never reached zero after the lease ran out";
  const double ramp_ticks = static_cast<double>(zero->tick - at_expiry->tick);
  EXPECT_GE(ramp_ticks, kRampMs - 5.0);   // ramped, not cut
  EXPECT_LE(ramp_ticks, kRampMs + 15.0);  // the ramp, plus the housekeeping period and a sample
  const ForceFigures device = force_figures(states);
  EXPECT_TRUE(device.all_finite);
  EXPECT_LE(device.max_step_per_tick, kMaxForceStepPerTick);
  State after;
  ASSERT_TRUE(observer.poll_state(after, milliseconds(500)));
  EXPECT_EQ(observer.stats().objects, 1u);  // the wall, registered again
  std::printf(
      "lan pulled cable: force %.2f N before; lease expiry to zero force %.0f ticks (ramp %.0f); "
      "largest change %.3f N/tick; resumed with a new session %.0f ms after the cable was back\n",
      norm(before.force), ramp_ticks, kRampMs, device.max_step_per_tick, reconnect_ms);
}

TEST(Lan, AServerRestartBehindALossyNetworkIsSurvivedWithinTwoSeconds) {
  auto first = std::make_unique<ServerProcess>(real_time_config(1000));
  const std::uint16_t grpc_port = first->grpc_port();
  const std::uint16_t udp_port = first->udp_port();
  const Impairment busy = kProfiles[1].impairment;
  TcpDelayRelay control(grpc_port, busy.delay);
  UdpImpairmentRelay data(udp_port, busy, busy, 17);
  ConnectionLog log;
  Client remote(remote_config(*first, control, data, "remote"));
  log.attach(remote);
  ObjectHandle wall = remote.add_wall({.normal = {0, 0, 1}, .impedance = {kWallStiffness, kWallDamping}});
  State state;
  ASSERT_TRUE(remote.poll_state(state, milliseconds(2000)));

  first.reset();
  const auto lost = log.wait(1, milliseconds(5000));
  ASSERT_TRUE(lost);
  EXPECT_EQ(lost->first.state, ConnectionChange::State::kLost);
  ServerProcess second(real_time_config(1000), {}, 0, grpc_port, udp_port);
  const auto resumed = log.wait(2, milliseconds(5000));
  ASSERT_TRUE(resumed);
  EXPECT_EQ(resumed->first.state, ConnectionChange::State::kResumed);
  EXPECT_TRUE(resumed->first.new_session);
  const double reconnect_ms =
      std::chrono::duration<double, std::milli>(resumed->second - second.ready_at()).count();
  EXPECT_LT(reconnect_ms, 2000.0);
  Client local(config_for(second, "local"));
  EXPECT_EQ(local.stats().objects, 1u);
  State streamed;
  ASSERT_TRUE(remote.poll_state(streamed, milliseconds(2000)));  // the stream carries on
  std::printf("lan restart (5 ms, 5 %% loss): resumed %.0f ms after the new server was ready\n",
              reconnect_ms);
}

}  // namespace
}  // namespace haptic::test
