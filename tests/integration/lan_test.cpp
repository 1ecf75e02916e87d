// A simulated LAN between an SDK client and a real-time hapticd (issue 11 item 6): delay, jitter,
// loss, duplication and reordering on the data plane, delay and a pulled cable on the control
// plane. What must hold: the client's counters account for every State the network dropped or
// duplicated; the force on the device stays bounded and never steps, whatever is lost; a lease
// that runs out ramps the session's items out, and the client comes back with them; a server
// restart is survived within 2 s. Each run prints its figures (rate, latency, loss, force).
//
// By default the impairment is done in user space (tests/support/*_relay.hpp), which works
// everywhere. tests/integration/lan_netem.sh runs the same tests with the server in a network
// namespace of its own, across a veth pair shaped by the kernel's netem (HAPTIC_LAN_NETNS names
// the namespace); it skips where namespaces or netem are missing.

#include <gtest/gtest.h>
#include <sys/time.h>

#include <algorithm>
#include <iterator>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
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

std::string real_time_config(int lease_ms, const std::string& host) {
  return R"({"time_mode": "REAL_TIME", "udp_address": ")" + host + R"(", "status_period_s": 0,
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

/// Every State a client accepts (through an observer: on_state sees only the newest of a
/// backlog, and a loaded machine makes backlogs), and the events its callback sees.
class Recorder {
 public:
  void attach(Client& client) { observing_ = client.observe(samples_); }
  void watch(Client& client) {
    client.on_event([this](const Event& event) {
      std::lock_guard lock(mutex_);
      events_.push_back(event);
    });
  }
  std::vector<State> states() const { return samples_->states(); }
  std::vector<Event> events() const {
    std::lock_guard lock(mutex_);
    return events_;
  }
  void clear() { samples_->clear(); }

 private:
  class Samples : public ReceiveObserver {
   public:
    void on_sample(const State& state) noexcept override {
      std::lock_guard lock(mutex_);
      states_.push_back(state);
    }
    std::vector<State> states() const {
      std::lock_guard lock(mutex_);
      return states_;
    }
    void clear() {
      std::lock_guard lock(mutex_);
      states_.clear();
    }

   private:
    mutable std::mutex mutex_;
    std::vector<State> states_;
  };
  std::shared_ptr<Samples> samples_ = std::make_shared<Samples>();
  ObserverHandle observing_;
  mutable std::mutex mutex_;
  std::vector<Event> events_;
};

double norm(const Vec3& v) { return std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }

/// What a stream of samples says about the force: the largest magnitude and the largest change
/// per loop period between samples (a gap of n periods allows n times the per-period change; the
/// gap is measured in server time, so the periods an overrun skipped count too: the hand's path
/// moved on meanwhile).
struct ForceFigures {
  double max_force = 0.0;          // N
  double max_step_per_tick = 0.0;  // N per loop period
  std::uint64_t at_tick = 0;       // where the largest change ended
  bool all_finite = true;
};

ForceFigures force_figures(std::vector<State> states, double period_s = 1e-3) {
  std::sort(states.begin(), states.end(), [](const State& a, const State& b) { return a.tick < b.tick; });
  ForceFigures figures;
  for (std::size_t i = 0; i < states.size(); ++i) {
    const Vec3& f = states[i].force;
    figures.all_finite = figures.all_finite && std::isfinite(f.x) && std::isfinite(f.y) && std::isfinite(f.z);
    figures.max_force = std::max(figures.max_force, norm(f));
    if (i == 0 || states[i].tick <= states[i - 1].tick) continue;
    const Vec3& g = states[i - 1].force;
    const double change = norm({f.x - g.x, f.y - g.y, f.z - g.z});
    const double periods = std::max<double>(
        static_cast<double>(states[i].tick - states[i - 1].tick),
        std::round((states[i].server_time - states[i - 1].server_time) / period_s));
    if (change / periods > figures.max_step_per_tick) {
      figures.max_step_per_tick = change / periods;
      figures.at_tick = states[i].tick;
    }
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

/// The remote client's wall at z = 0, then (through the observer) the hand. The hand moves only
/// once the wall has ramped in: a wall that ramps in around a tool already deep inside it (a slow
/// start on a loaded machine) would be another test.
ObjectHandle wall_then_hand(Client& remote, Client& observer, const OperatorInput& hand) {
  ObjectHandle wall = remote.add_wall({.normal = {0, 0, 1}, .impedance = {kWallStiffness, kWallDamping}});
  std::this_thread::sleep_for(milliseconds(100));
  observer.set_operator(hand);
  return wall;
}

/// The network between a test's clients and its server.
class Network {
 public:
  virtual ~Network() = default;
  virtual const char* kind() const = 0;
  /// Starts hapticd on the far side; given ports (not 0) are bound again: a restart.
  virtual std::unique_ptr<ServerProcess> start_server(int lease_ms, std::uint16_t grpc_port = 0,
                                                      std::uint16_t udp_port = 0) = 0;
  /// Both directions' impairment, from now on.
  virtual void set(const Impairment& impairment) = 0;
  /// A pulled cable (both planes), or put back.
  virtual void set_partitioned(bool partitioned) = 0;
  /// A client across the network, heartbeating at the SDK's default period as a LAN client does.
  virtual ClientConfig remote(const ServerProcess& server, const char* name) const = 0;
  /// A client watching the device: beside the server where the network allows it.
  virtual ClientConfig local(const ServerProcess& server, const char* name) const = 0;
  /// Whether local() clients bypass the network (and its pulled cable).
  virtual bool local_is_beside_server() const = 0;
  /// What the network did to the States it carried to the remote client, where it can tell.
  virtual std::optional<RelayCounters> to_client_counters() const { return std::nullopt; }
};

/// User-space relays on loopback; the observer goes direct.
class RelayNetwork final : public Network {
 public:
  const char* kind() const override { return "relay"; }
  std::unique_ptr<ServerProcess> start_server(int lease_ms, std::uint16_t grpc_port,
                                              std::uint16_t udp_port) override {
    auto server = std::make_unique<ServerProcess>(real_time_config(lease_ms, "127.0.0.1"), std::string(),
                                                  0, grpc_port, udp_port);
    if (!data_) {  // a restart keeps its ports, so the relays stay
      control_ = std::make_unique<TcpDelayRelay>(server->grpc_port(), impairment_.delay);
      data_ = std::make_unique<UdpImpairmentRelay>(server->udp_port(), impairment_, impairment_, ++seed_);
    }
    return server;
  }
  void set(const Impairment& impairment) override {
    impairment_ = impairment;
    if (control_) control_->set_delay(impairment.delay);
    if (data_) data_->set(impairment, impairment);
  }
  void set_partitioned(bool partitioned) override {
    control_->set_partitioned(partitioned);
    data_->set_partitioned(partitioned);
  }
  ClientConfig remote(const ServerProcess& server, const char* name) const override {
    ClientConfig config = config_for(server, name);
    config.server_address = control_->address();
    config.udp_address = data_->address();
    config.heartbeat_period = milliseconds(100);
    return config;
  }
  ClientConfig local(const ServerProcess& server, const char* name) const override {
    return config_for(server, name);
  }
  bool local_is_beside_server() const override { return true; }
  std::optional<RelayCounters> to_client_counters() const override { return data_->to_client_counters(); }

 private:
  Impairment impairment_;
  std::uint64_t seed_ = 10;
  std::unique_ptr<TcpDelayRelay> control_;
  std::unique_ptr<UdpImpairmentRelay> data_;
};

/// The server in the network namespace lan_netem.sh made, across a veth pair shaped by netem on
/// both ends; this process runs in the client's namespace. Every client crosses it.
class NetemNetwork final : public Network {
 public:
  explicit NetemNetwork(std::string server_namespace)
      : namespace_(std::move(server_namespace)),
        server_ip_(environment("HAPTIC_LAN_SERVER_IP")),
        client_device_(environment("HAPTIC_LAN_CLIENT_DEV")),
        server_device_(environment("HAPTIC_LAN_SERVER_DEV")) {}
  const char* kind() const override { return "netem"; }
  std::unique_ptr<ServerProcess> start_server(int lease_ms, std::uint16_t grpc_port,
                                              std::uint16_t udp_port) override {
    const ServerHost host{{"ip", "netns", "exec", namespace_}, server_ip_};
    // Not loopback: the server asks for TLS and tokens unless told this network is a test's own.
    return std::make_unique<ServerProcess>(real_time_config(lease_ms, server_ip_), "--insecure", 0,
                                           grpc_port, udp_port, host);
  }
  void set(const Impairment& impairment) override {
    impairment_ = impairment;
    apply(netem_arguments(impairment));
  }
  void set_partitioned(bool partitioned) override {
    apply(partitioned ? std::string("loss 100%") : netem_arguments(impairment_));
  }
  ClientConfig remote(const ServerProcess& server, const char* name) const override {
    ClientConfig config = config_for(server, name);
    config.heartbeat_period = milliseconds(100);
    return config;
  }
  ClientConfig local(const ServerProcess& server, const char* name) const override {
    return config_for(server, name);
  }
  bool local_is_beside_server() const override { return false; }

 private:
  static std::string environment(const char* name) {
    const char* value = std::getenv(name);
    if (value == nullptr || *value == '\0') throw std::runtime_error(std::string(name) + " is not set");
    return value;
  }
  static std::string netem_arguments(const Impairment& impairment) {
    std::string arguments = "delay " + std::to_string(impairment.delay.count()) + "us " +
                            std::to_string(impairment.jitter.count()) + "us";
    if (impairment.loss > 0) arguments += " loss " + std::to_string(100.0 * impairment.loss) + "%";
    if (impairment.duplicate > 0) arguments += " duplicate " + std::to_string(100.0 * impairment.duplicate) + "%";
    if (impairment.reorder > 0) arguments += " reorder " + std::to_string(100.0 * impairment.reorder) + "%";
    return arguments;
  }
  void apply(const std::string& arguments) const {
    const std::string here = "tc qdisc replace dev " + client_device_ + " root netem " + arguments;
    const std::string there = "ip netns exec " + namespace_ + " tc qdisc replace dev " + server_device_ +
                              " root netem " + arguments;
    if (std::system(here.c_str()) != 0 || std::system(there.c_str()) != 0) {
      throw std::runtime_error("netem: '" + here + "' or its twin in " + namespace_ + " failed");
    }
  }
  std::string namespace_;
  std::string server_ip_;
  std::string client_device_;
  std::string server_device_;
  Impairment impairment_;
};

/// The network of this run: netem where lan_netem.sh set one up, else the relays.
std::unique_ptr<Network> make_network(const Impairment& impairment) {
  std::unique_ptr<Network> network;
  if (const char* name = std::getenv("HAPTIC_LAN_NETNS"); name != nullptr && *name != '\0') {
    network = std::make_unique<NetemNetwork>(name);
  } else {
    network = std::make_unique<RelayNetwork>();
  }
  network->set(impairment);
  return network;
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
  // Room for every datagram the relay may hand over at once: a reader held up on a loaded machine
  // must not lose any in the kernel, or the count below would blame the relay for it.
  const int buffer = 4 << 20;
  ::setsockopt(server, SOL_SOCKET, SO_RCVBUF, &buffer, sizeof(buffer));
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
  std::atomic<int> received{0};
  double shortest_ms = 1e9;
  std::atomic<bool> stop_reading{false};
  std::thread reader([&] {  // reads as they come, so the stand-in's buffer never overflows
    int index = 0;
    while (!stop_reading.load()) {
      if (::recv(server, &index, sizeof(index), 0) != static_cast<ssize_t>(sizeof(index))) continue;
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
  // Until the relay has passed on all it took in and the reader has them (or 10 s).
  const auto give_up = steady_clock::now() + std::chrono::seconds(10);
  for (;;) {
    const RelayCounters now = relay.to_server_counters();
    const bool settled = now.received == static_cast<std::uint64_t>(kSent) &&
                         now.delivered == now.received - now.dropped + now.duplicated;
    if ((settled && static_cast<std::uint64_t>(received.load()) == now.delivered) || steady_clock::now() > give_up) break;
    std::this_thread::sleep_for(milliseconds(10));
  }
  stop_reading = true;
  reader.join();
  const RelayCounters counters = relay.to_server_counters();
  EXPECT_EQ(counters.received, static_cast<std::uint64_t>(kSent));
  EXPECT_EQ(counters.delivered, counters.received - counters.dropped + counters.duplicated);
  EXPECT_EQ(static_cast<std::uint64_t>(received.load()), counters.delivered);
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
  const auto network = make_network(profile.impairment);
  const auto server = network->start_server(1000);
  ASSERT_TRUE(server->time_origin().has_value());

  // An observer sees the device's force (beside the server, where the network allows it).
  Recorder truth;  // before the client whose callbacks it takes, so it outlives them
  Client observer(network->local(*server, "observer"));
  truth.attach(observer);
  truth.watch(observer);

  Recorder seen;
  Client remote(network->remote(*server, "remote"));
  seen.attach(remote);
  ObjectHandle wall = wall_then_hand(remote, observer, stroke_through_wall());
  const auto start = steady_clock::now();
  const std::uint64_t accepted_before = remote.receive_counters().accepted;
  std::this_thread::sleep_for(milliseconds(3000));
  const std::uint64_t accepted_during = remote.receive_counters().accepted - accepted_before;
  const double seconds = std::chrono::duration<double>(steady_clock::now() - start).count();
  remote.subscribe(0);  // the stream stops; what is on its way arrives
  std::this_thread::sleep_for(milliseconds(150));
  // On a loaded machine the relay or the client's reader may still be behind: until the client
  // has taken in all the network passed on (polled, at most 10 s more).
  const auto drained_by = steady_clock::now() + std::chrono::seconds(10);
  while (steady_clock::now() < drained_by) {
    const auto passed_on = network->to_client_counters();
    if (!passed_on) break;
    const ReceiveCounters taken_in = remote.receive_counters();
    if (taken_in.accepted + taken_in.duplicates ==
        passed_on->states_received - passed_on->states_dropped + passed_on->states_duplicated) {
      break;
    }
    std::this_thread::sleep_for(milliseconds(20));
  }

  const ReceiveCounters counters = remote.receive_counters();
  const std::vector<State> states = seen.states();
  ASSERT_FALSE(states.empty());
  EXPECT_EQ(counters.rejected, 0u);
  // The server numbers every sample due to the client, so those its sender skipped when it had
  // fallen behind (a busy host) are gaps the client counts lost too; the server counts them for
  // this client (samples_unsent). The rest is the network's loss (binomial; ±5 points is over
  // 5 σ here).
  std::uint64_t unsent = 0;
  for (const ClientStats& c : observer.stats().clients) {
    if (c.session_id == remote.session_id()) unsent = c.samples_unsent;
  }
  const std::uint64_t network_lost = counters.lost > unsent ? counters.lost - unsent : 0;
  const double seen_loss =
      static_cast<double>(network_lost) / static_cast<double>(counters.accepted + network_lost);
  EXPECT_NEAR(seen_loss, profile.impairment.loss, 0.05) << unsent << " skipped by the server";
  if (const auto network_counters = network->to_client_counters()) {
    // Every State the server sent arrived once or was dropped on the way, and the SDK tells
    // which: its lost count misses only drops after the last State to arrive.
    EXPECT_EQ(counters.accepted, network_counters->states_received - network_counters->states_dropped);
    EXPECT_EQ(counters.duplicates, network_counters->states_duplicated);
    EXPECT_LE(counters.lost, network_counters->states_dropped + unsent);
    // Drops after the last State to arrive are never seen as gaps: ten in a row at 30 % loss
    // is a chance of 6e-6.
    EXPECT_GE(counters.lost + 10, network_counters->states_dropped);
  }

  std::vector<double> latency_ms;
  for (const State& state : states) {
    const auto stamped = *server->time_origin() + std::chrono::nanoseconds(std::llround(state.server_time * 1e9));
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
  EXPECT_LE(device.max_step_per_tick, kMaxForceStepPerTick) << "at tick " << device.at_tick;
  EXPECT_LE(remote_view.max_step_per_tick, kMaxForceStepPerTick) << "at tick " << remote_view.at_tick;
  EXPECT_EQ(observer.stats().objects, 1u);

  std::printf(
      "lan %s %-15s: %.0f States/s received, %.1f %% lost (%llu duplicates, %llu reordered); "
      "latency p50 %.2f ms, p99 %.2f ms; force max %.2f N, largest change %.3f N/tick (device), "
      "%.3f N/tick (as received)\n",
      network->kind(), profile.name, static_cast<double>(accepted_during) / seconds, 100.0 * seen_loss,
      static_cast<unsigned long long>(counters.duplicates), static_cast<unsigned long long>(counters.reordered),
      p50, p99, device.max_force, device.max_step_per_tick, remote_view.max_step_per_tick);
}

std::string profile_name(const ::testing::TestParamInfo<Profile>& param) { return param.param.name; }
INSTANTIATE_TEST_SUITE_P(Profiles, LanProfile, ::testing::ValuesIn(kProfiles), profile_name);

TEST(Lan, APulledCableRampsTheForceOutAtLeaseExpiryAndTheClientComesBackWithItsWall) {
  constexpr int kLeaseMs = 600;
  const auto network = make_network(kProfiles[0].impairment);
  const auto server = network->start_server(kLeaseMs);

  Recorder truth;
  Client observer(network->local(*server, "observer"));
  truth.attach(observer);
  truth.watch(observer);

  ConnectionLog log;
  Client remote(network->remote(*server, "remote"));
  log.attach(remote);
  ObjectHandle wall = wall_then_hand(remote, observer, press_into_wall());
  const std::uint64_t first_session = remote.session_id();
  // Pressed in and settled: on an idle machine within 800 ms; a loaded one is given up to 5 s.
  State before;
  const auto pressed_by = std::chrono::steady_clock::now() + milliseconds(5000);
  std::this_thread::sleep_for(milliseconds(800));
  do {
    ASSERT_TRUE(observer.poll_state(before, milliseconds(500)));
  } while (norm(before.force) <= 3.0 && std::chrono::steady_clock::now() < pressed_by);
  ASSERT_GT(norm(before.force), 3.0) << "the hand is not pressing into the wall";

  network->set_partitioned(true);
  const auto lost = log.wait(1, milliseconds(3000));
  ASSERT_TRUE(lost);
  EXPECT_EQ(lost->first.state, ConnectionChange::State::kLost);
  // The cable stays out until the lease has run out and the force has ramped to zero (a client
  // back sooner would ramp its wall in over the old one's ramp out): seen by the observer where it
  // sits beside the server (polled, at most 10 s), else given the lease and 400 ms.
  if (network->local_is_beside_server()) {
    const auto ramped_out = [&] {
      const std::vector<Event> events = truth.events();
      const auto expiry = std::find_if(events.begin(), events.end(), [&](const Event& e) {
        return e.kind == Event::Kind::kLeaseExpired && e.session_id == first_session;
      });
      if (expiry == events.end()) return false;
      const std::vector<State> seen_so_far = truth.states();
      return std::any_of(seen_so_far.begin(), seen_so_far.end(), [&](const State& s) {
        return s.server_time >= expiry->server_time && norm(s.force) == 0.0;
      });
    };
    const auto give_up = steady_clock::now() + milliseconds(10000);
    while (!ramped_out() && steady_clock::now() < give_up) std::this_thread::sleep_for(milliseconds(20));
    ASSERT_TRUE(ramped_out()) << "the first session's lease did not run out, or its wall did not ramp out";
  } else {
    std::this_thread::sleep_for(milliseconds(kLeaseMs + 400));
  }
  const auto reconnected_from = steady_clock::now();
  network->set_partitioned(false);
  const auto resumed = log.wait(2, milliseconds(10000));  // idle, within the backoff's 1 s: printed
  ASSERT_TRUE(resumed);
  EXPECT_EQ(resumed->first.state, ConnectionChange::State::kResumed);
  EXPECT_TRUE(resumed->first.new_session);
  EXPECT_EQ(resumed->first.items_not_restored, 0u);
  EXPECT_NE(remote.session_id(), first_session);
  const double reconnect_ms =
      std::chrono::duration<double, std::milli>(resumed->second - reconnected_from).count();
  std::this_thread::sleep_for(milliseconds(300));  // the wall ramps back in and pushes the tool out

  // The lease ran out once, for the first session; from that tick the force went to zero over
  // the removal ramp, with no step, and came back the same way. (Only an observer the cable
  // does not cut sees the ramp: across netem it lost its own stream and lease meanwhile.)
  std::vector<State> states = truth.states();
  std::sort(states.begin(), states.end(), [](const State& a, const State& b) { return a.tick < b.tick; });
  double ramp_ticks = -1.0;
  if (network->local_is_beside_server()) {
    const std::vector<Event> events = truth.events();
    const auto expiry = std::find_if(events.begin(), events.end(), [&](const Event& e) {
      return e.kind == Event::Kind::kLeaseExpired && e.session_id == first_session;
    });
    ASSERT_NE(expiry, events.end());
      // The loop skips the periods an overrun lost, so ticks are found by their time stamps: the
    // last sample stamped before the expiry and the first zero force after it (every sample the
    // observer accepted; the network may still have lost some, so these can only be early or
    // late by a lost sample's tick).
    const auto after = std::find_if(states.begin(), states.end(), [&](const State& s) {
      return s.server_time >= expiry->server_time;
    });
    ASSERT_NE(after, states.begin());
    ASSERT_NE(after, states.end());
    const auto before_expiry = std::prev(after);
    const auto zero = std::find_if(after, states.end(), [&](const State& s) { return norm(s.force) == 0.0; });
    ASSERT_NE(zero, states.end()) << "the force never reached zero after the lease ran out";
    ramp_ticks = static_cast<double>(zero->tick - before_expiry->tick);
    EXPECT_GE(ramp_ticks, kRampMs - 5.0);  // ramped, not cut
    // The ramp, plus the housekeeping period, plus what a stalled observer missed on either side.
    EXPECT_LE(ramp_ticks, kRampMs + 60.0);
  }
  const ForceFigures device = force_figures(states);
  EXPECT_TRUE(device.all_finite);
  EXPECT_LE(device.max_step_per_tick, kMaxForceStepPerTick) << "at tick " << device.at_tick;
  if (HasFailure()) {  // the observer's samples around the largest change, and the events
    for (const State& s : states) {
      if (s.tick + 60 >= device.at_tick && s.tick <= device.at_tick + 5) {
        std::printf("  tick %llu t %.4f F %.3f %.3f %.3f p %.5f contacts %u flags %u\n",
                    static_cast<unsigned long long>(s.tick), s.server_time, s.force.x, s.force.y,
                    s.force.z, s.position.z, s.contact_count, s.flags);
      }
    }
    for (const Event& e : truth.events()) {
      std::printf("  event %d session %llu t %.4f %s\n", static_cast<int>(e.kind),
                  static_cast<unsigned long long>(e.session_id), e.server_time, e.message.c_str());
    }
  }
  State after;
  ASSERT_TRUE(observer.poll_state(after, milliseconds(500)));
  EXPECT_EQ(observer.stats().objects, 1u);  // the wall, registered again
  std::printf(
      "lan %s pulled cable: force %.2f N before; lease expiry to zero force %.0f ticks (ramp %.0f); "
      "largest change %.3f N/tick; resumed with a new session %.0f ms after the cable was back\n",
      network->kind(), norm(before.force), ramp_ticks, kRampMs, device.max_step_per_tick, reconnect_ms);
}

TEST(Lan, AServerRestartBehindALossyNetworkIsSurvivedWithANewSession) {
  const auto network = make_network(kProfiles[1].impairment);
  auto first = network->start_server(1000);
  const std::uint16_t grpc_port = first->grpc_port();
  const std::uint16_t udp_port = first->udp_port();
  ConnectionLog log;
  Client remote(network->remote(*first, "remote"));
  log.attach(remote);
  ObjectHandle wall = remote.add_wall({.normal = {0, 0, 1}, .impedance = {kWallStiffness, kWallDamping}});
  State state;
  ASSERT_TRUE(remote.poll_state(state, milliseconds(2000)));

  first.reset();
  const auto lost = log.wait(1, milliseconds(5000));
  ASSERT_TRUE(lost);
  EXPECT_EQ(lost->first.state, ConnectionChange::State::kLost);
  const auto second = network->start_server(1000, grpc_port, udp_port);
  const auto resumed = log.wait(2, milliseconds(10000));  // idle, within the backoff's 1 s: printed
  ASSERT_TRUE(resumed);
  EXPECT_EQ(resumed->first.state, ConnectionChange::State::kResumed);
  EXPECT_TRUE(resumed->first.new_session);
  const double reconnect_ms =
      std::chrono::duration<double, std::milli>(resumed->second - second->ready_at()).count();
  Client local(network->local(*second, "local"));
  EXPECT_EQ(local.stats().objects, 1u);
  State streamed;
  ASSERT_TRUE(remote.poll_state(streamed, milliseconds(2000)));  // the stream carries on
  std::printf("lan %s restart (5 ms, 5 %% loss): resumed %.0f ms after the new server was ready\n",
              network->kind(), reconnect_ms);
}

}  // namespace
}  // namespace haptic::test
