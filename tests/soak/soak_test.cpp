// Faults and load against a real-time hapticd (label soak: scripts/soak). Each test prints what it
// measured ("soak: ..." lines, gathered in docs/reliability.md) and asserts behaviour: forces reach
// zero through a ramp, never a step; nobody else is disturbed; the server keeps serving.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <haptic/haptic.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "haptic/v1/service.grpc.pb.h"
#include "integration/raw_client.hpp"
#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"
#include "recording/recording_file.hpp"

namespace haptic {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;
using std::chrono::steady_clock;

constexpr int kLeaseMs = 500;
constexpr double kRampMs = 50.0;  // the default removal_ramp_ms
// The largest force change from one tick to the next a ramp may make here: the hand (800 N/m)
// presses the tool deeper as the wall gives, so the fall is steeper than the contact force / 50
// (0.15 N a tick measured from 4.4 N); a cut without the ramp would step by the whole force.
constexpr double kMaxForceStepPerTick = 1.0;  // N

/// A real-time server with the lease `lease_ms` and `extra` fields spliced in.
std::string real_time_config(const std::string& extra = {}, int lease_ms = kLeaseMs) {
  return R"({"time_mode": "REAL_TIME", "status_period_s": 0, "real_time": {"use_fifo": false},
    "lease_timeout_ms": )" + std::to_string(lease_ms) +
         R"(, "simulated_point_mass": {"initial_position": {"z": 0.005}})" +
         (extra.empty() ? "" : ", " + extra) + "}";
}

double seconds_since(steady_clock::time_point start) {
  return std::chrono::duration<double>(steady_clock::now() - start).count();
}

/// soak_client in a process of its own: a wall and a hand pressing into it.
class WallClientProcess {
 public:
  explicit WallClientProcess(const std::string& address) {
    int fds[2];
    if (::pipe(fds) != 0) throw std::runtime_error("pipe");
    std::string binary = SOAK_CLIENT_BINARY;
    std::string argument = address;
    char* argv[] = {binary.data(), argument.data(), nullptr};
    const pid_t parent = ::getpid();
    pid_ = ::fork();
    if (pid_ == 0) {
      ::prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (::getppid() != parent) ::_exit(127);
      ::dup2(fds[1], STDOUT_FILENO);
      ::close(fds[0]);
      ::execv(argv[0], argv);
      ::_exit(127);
    }
    ::close(fds[1]);
    out_ = fds[0];
  }
  ~WallClientProcess() {
    if (pid_ > 0) {
      ::kill(pid_, SIGCONT);
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    ::close(out_);
  }
  /// True once it has printed "ready" (its wall and hand are registered).
  bool wait_ready() {
    char buffer[16] = {};
    return ::read(out_, buffer, sizeof buffer) > 0 && std::string(buffer).rfind("ready", 0) == 0;
  }
  void signal(int number) { ::kill(pid_, number); }

 private:
  pid_t pid_ = -1;
  int out_ = -1;
};

/// Every State an observer receives: server time, tick, |force|.
class ForceTrace {
 public:
  struct Point {
    double server_time;
    std::uint64_t tick;
    double force;
  };
  void attach(Client& client) {
    client.on_state([this](const State& state) {
      const double f = std::sqrt(state.force.x * state.force.x + state.force.y * state.force.y +
                                 state.force.z * state.force.z);
      std::lock_guard lock(mutex_);
      points_.push_back({state.server_time, state.tick, f});
    });
  }
  std::vector<Point> points() const {
    std::lock_guard lock(mutex_);
    return points_;
  }
  /// Waits until `holds` has been true of every point for `span_s` of server time; false after
  /// `timeout`.
  template <typename Predicate>
  bool wait_for(Predicate holds, double span_s, milliseconds timeout) const {
    const auto give_up = steady_clock::now() + timeout;
    while (steady_clock::now() < give_up) {
      {
        std::lock_guard lock(mutex_);
        if (!points_.empty()) {
          const double newest = points_.back().server_time;
          double since = newest;
          for (auto it = points_.rbegin(); it != points_.rend() && holds(it->force); ++it) since = it->server_time;
          if (newest - since >= span_s) return true;
        }
      }
      std::this_thread::sleep_for(milliseconds(10));
    }
    return false;
  }

 private:
  mutable std::mutex mutex_;
  std::vector<Point> points_;
};

/// What happened to the force after `from_s` (server time): when it started to fall, when it
/// reached zero, the largest change between consecutive ticks.
struct Fade {
  double contact_force = 0.0;
  double fall_start_s = NAN;
  double zero_s = NAN;
  double largest_step = 0.0;
  std::uint64_t ramp_ticks = 0;
};

Fade fade_after(const std::vector<ForceTrace::Point>& points, double from_s) {
  Fade fade;
  const ForceTrace::Point* previous = nullptr;
  for (const ForceTrace::Point& p : points) {
    if (p.server_time < from_s) {
      fade.contact_force = p.force;
      previous = &p;
      continue;
    }
    if (std::isnan(fade.fall_start_s) && p.force < 0.97 * fade.contact_force) fade.fall_start_s = p.server_time;
    if (previous != nullptr && p.tick == previous->tick + 1 && !std::isnan(fade.fall_start_s)) {
      fade.largest_step = std::max(fade.largest_step, std::abs(p.force - previous->force));
    }
    if (!std::isnan(fade.fall_start_s) && std::isnan(fade.zero_s)) ++fade.ramp_ticks;
    if (std::isnan(fade.zero_s) && p.force < 1e-9) fade.zero_s = p.server_time;
    previous = &p;
  }
  return fade;
}

double server_now_s(const test::ServerProcess& server) {
  return std::chrono::duration<double>(steady_clock::now() - *server.time_origin()).count();
}

/// A real-time server, an observer tracing the device's force, and soak_client in contact.
struct ContactRig {
  ContactRig() {
    trace.attach(observer);
    in_contact = wall.wait_ready() && trace.wait_for([](double f) { return f > 2.0; }, 0.3, seconds(5));
  }
  test::ServerProcess server{real_time_config()};
  ForceTrace trace;
  Client observer{test::config_for(server, "observer")};
  WallClientProcess wall{server.address()};
  bool in_contact = false;

  /// Sends the wall's client `signal_number` and waits (up to 5 s) for the force to have been
  /// zero for `settled_s`; the force's fall from that moment, which `at_s` (server time) gets.
  std::optional<Fade> silence(int signal_number, double settled_s, double& at_s) {
    at_s = server_now_s(server);
    wall.signal(signal_number);
    if (!trace.wait_for([](double f) { return f < 1e-9; }, settled_s, seconds(5))) return std::nullopt;
    return fade_after(trace.points(), at_s);
  }
};

TEST(Soak, AClientKilledMidContactLosesItsForceThroughTheRampAfterItsLease) {
  ContactRig rig;
  ASSERT_TRUE(rig.in_contact);
  double killed_at = 0.0;
  const std::optional<Fade> faded = rig.silence(SIGKILL, 0.2, killed_at);
  ASSERT_TRUE(faded) << "the force did not reach zero";
  const Fade& fade = *faded;
  const double to_zero_ms = (fade.zero_s - killed_at) * 1e3;
  const double ramp_ms = (fade.zero_s - fade.fall_start_s) * 1e3;
  std::printf("soak: SIGKILL mid-contact (%.2f N): force zero %.0f ms after the kill (lease %d ms + "
              "ramp %.0f ms); ramp %.0f ms over %llu ticks, largest step %.3f N\n",
              fade.contact_force, to_zero_ms, kLeaseMs, kRampMs, ramp_ms,
              static_cast<unsigned long long>(fade.ramp_ticks), fade.largest_step);
  // Not before the lease could have run out (its last heartbeat came at most 100 ms before the
  // kill), and through the ramp, never a step.
  EXPECT_GT(to_zero_ms, kLeaseMs - 110.0);
  EXPECT_GE(fade.ramp_ticks, 40u);
  EXPECT_LE(fade.largest_step, kMaxForceStepPerTick);
  EXPECT_EQ(rig.observer.stats().leases_expired, 1u);
}

TEST(Soak, AStoppedClientLosesItsLeaseWithoutDisturbingOthersAndComesBackWhenContinued) {
  ContactRig rig;
  ASSERT_TRUE(rig.in_contact);
  double stopped_at = 0.0;
  const std::optional<Fade> faded = rig.silence(SIGSTOP, 0.3, stopped_at);
  ASSERT_TRUE(faded) << "the force did not reach zero";
  const Fade& fade = *faded;
  ForceTrace& trace = rig.trace;
  EXPECT_EQ(rig.observer.stats().leases_expired, 1u);
  // The observer's stream went on throughout: no gap longer than 100 ms in server time.
  double largest_gap = 0.0;
  const auto points = trace.points();
  for (std::size_t i = 1; i < points.size(); ++i) {
    if (points[i].server_time >= stopped_at) {
      largest_gap = std::max(largest_gap, points[i].server_time - points[i - 1].server_time);
    }
  }
  const auto continued = steady_clock::now();
  rig.wall.signal(SIGCONT);
  // Its SDK finds the session gone, opens a new one and registers the wall again.
  const bool back = trace.wait_for([](double f) { return f > 2.0; }, 0.1, seconds(10));
  std::printf("soak: SIGSTOP mid-contact: force zero %.0f ms after the stop (ramp %llu ticks, "
              "largest step %.3f N); the observer's largest gap %.1f ms; after SIGCONT the wall "
              "is back in %.0f ms\n",
              (fade.zero_s - stopped_at) * 1e3, static_cast<unsigned long long>(fade.ramp_ticks),
              fade.largest_step, largest_gap * 1e3, seconds_since(continued) * 1e3);
  EXPECT_GE(fade.ramp_ticks, 40u);
  EXPECT_LE(fade.largest_step, kMaxForceStepPerTick);
  EXPECT_LT(largest_gap, 0.1);
  EXPECT_TRUE(back) << "the continued client did not come back";
}

/// A duration from the environment (SOAK_SECONDS), for a quicker look; default `fallback`.
double soak_seconds(double fallback) {
  const char* text = std::getenv("SOAK_SECONDS");
  return text != nullptr ? std::atof(text) : fallback;
}

TEST(Soak, SixtyFourClientsAtOneKilohertz) {
  constexpr int kClients = 64;
  const double run_s = soak_seconds(60.0);
  test::ServerProcess server(real_time_config(
      R"("max_sessions": 80, "max_sessions_per_peer": 80, "session_open_rate_per_peer": 1000,
         "session_open_burst_per_peer": 100)", 2000));
  ClientConfig admin_config = test::config_for(server, "admin");
  admin_config.state_decimation = 0;
  Client admin(admin_config);
  std::this_thread::sleep_for(seconds(3));
  const Stats before = admin.stats();

  std::vector<std::unique_ptr<Client>> clients;
  for (int i = 0; i < kClients; ++i) {
    ClientConfig config = test::config_for(server, ("c" + std::to_string(i)).c_str());
    config.heartbeat_period = milliseconds(100);
    clients.push_back(std::make_unique<Client>(config));
  }
  std::this_thread::sleep_for(seconds(1));  // every stream started
  std::vector<std::uint64_t> start_counts;
  for (auto& client : clients) start_counts.push_back(client->receive_counters().accepted);
  const Stats load_start = admin.stats();
  const auto started = steady_clock::now();
  std::this_thread::sleep_for(std::chrono::duration<double>(run_s));
  const double elapsed = seconds_since(started);
  const Stats after = admin.stats();
  std::vector<double> rates;
  std::uint64_t lost = 0;
  for (int i = 0; i < kClients; ++i) {
    const ReceiveCounters counters = clients[i]->receive_counters();
    rates.push_back(static_cast<double>(counters.accepted - start_counts[i]) / elapsed);
    lost += counters.lost;
  }
  std::sort(rates.begin(), rates.end());
  std::vector<double> round_trips;
  for (const ClientStats& c : after.clients) {
    if (c.round_trip_samples > 0) round_trips.push_back(c.round_trip_p99_us);
  }
  std::sort(round_trips.begin(), round_trips.end());
  const double loop_rate = static_cast<double>(after.ticks - load_start.ticks) / elapsed;
  std::printf("soak: %d clients at 1 kHz for %.0f s: loop %.1f Hz, overruns %llu before (3 s, 1 "
              "client) and %llu during; lateness p99 %.0f us before, %.0f us at the end (10 s "
              "window), p99.9 %.0f us; per client %.0f / %.0f / %.0f states a second (min / median "
              "/ max), %llu lost in all; send delay p99 %.0f us; round trip p99 median %.0f us, "
              "largest %.0f us; leases expired %llu\n",
              kClients, elapsed, loop_rate, static_cast<unsigned long long>(before.overruns),
              static_cast<unsigned long long>(after.overruns - load_start.overruns),
              before.lateness_p99_us, after.lateness_p99_us, after.lateness_p999_us, rates.front(),
              rates[rates.size() / 2], rates.back(), static_cast<unsigned long long>(lost),
              after.send_delay_p99_us, round_trips.empty() ? 0.0 : round_trips[round_trips.size() / 2],
              round_trips.empty() ? 0.0 : round_trips.back(),
              static_cast<unsigned long long>(after.leases_expired));
  EXPECT_EQ(after.leases_expired, 0u);
  EXPECT_EQ(after.sessions, static_cast<std::uint32_t>(kClients + 1));
  EXPECT_GT(rates.front(), 0.0);  // every client was served
}

TEST(Soak, AThousandSessions) {
  constexpr int kSessions = 1000;
  test::ServerProcess server(real_time_config(
      R"("max_sessions": 1100, "max_sessions_per_peer": 1100, "session_open_rate_per_peer": 1000,
         "session_open_burst_per_peer": 1100)", 120000));
  test::RawClient raw(server.address());
  v1::OpenSessionResponse admin;
  ASSERT_TRUE(raw.open(admin, "admin").ok());
  const v1::Stats before = raw.stats(admin);
  std::vector<v1::OpenSessionResponse> sessions(kSessions);
  const auto opening = steady_clock::now();
  for (int i = 0; i < kSessions; ++i) {
    ASSERT_TRUE(raw.open(sessions[i], "s" + std::to_string(i)).ok()) << i;
  }
  const double open_s = seconds_since(opening);
  const auto stats_at = steady_clock::now();
  const v1::Stats during = raw.stats(admin);
  const double stats_ms = seconds_since(stats_at) * 1e3;
  v1::SessionRef ref;
  ref.set_session_id(admin.session_id());
  v1::SessionList list;
  ASSERT_TRUE(raw.call(&v1::Haptic::Stub::ListSessions, ref, list, admin.session_secret()).ok());
  EXPECT_EQ(list.sessions_size(), kSessions + 1);
  EXPECT_EQ(during.clients_size(), kSessions + 1);
  EXPECT_EQ(during.sessions(), static_cast<std::uint32_t>(kSessions + 1));
  const auto closing = steady_clock::now();
  for (const v1::OpenSessionResponse& session : sessions) {
    v1::SessionRef mine;
    mine.set_session_id(session.session_id());
    v1::Empty empty;
    ASSERT_TRUE(raw.call(&v1::Haptic::Stub::CloseSession, mine, empty, session.session_secret()).ok());
  }
  const double close_s = seconds_since(closing);
  const v1::Stats after = raw.stats(admin);
  std::printf("soak: %d sessions: opened in %.2f s (%.2f ms each), GetStats with %d clients in "
              "%.1f ms, closed in %.2f s; loop overruns %llu meanwhile, lateness p99 %.0f us\n",
              kSessions, open_s, open_s * 1e3 / kSessions, kSessions + 1, stats_ms, close_s,
              static_cast<unsigned long long>(after.overruns() - before.overruns()),
              after.lateness_p99_us());
  EXPECT_EQ(after.sessions(), 1u);
}

TEST(Soak, TenThousandItemsInOneSession) {
  constexpr int kItems = 10000;
  test::ServerProcess server(real_time_config(R"("max_objects_per_session": 10000)", 120000));
  test::RawClient raw(server.address());
  v1::OpenSessionResponse session;
  ASSERT_TRUE(raw.open(session, "crowd").ok());
  std::this_thread::sleep_for(seconds(2));
  const v1::Stats before = raw.stats(session);
  // A 100 × 100 grid of small spheres 3 cm apart, 5 cm below the tool.
  v1::ApplySceneRequest request;
  request.set_session_id(session.session_id());
  for (int i = 0; i < kItems; ++i) {
    v1::Object& sphere = *request.mutable_scene()->add_objects();
    sphere.mutable_pose()->mutable_position()->set_x(0.03 * (i % 100 - 50));
    sphere.mutable_pose()->mutable_position()->set_y(0.03 * (i / 100 - 50));
    sphere.mutable_pose()->mutable_position()->set_z(-0.05);
    sphere.mutable_sphere()->set_radius(0.005);
    sphere.mutable_impedance()->set_stiffness(500.0);
  }
  v1::ApplySceneResponse applied;
  const auto applying = steady_clock::now();
  ASSERT_TRUE(raw.call(&v1::Haptic::Stub::ApplyScene, request, applied, session.session_secret(),
                       seconds(60)).ok());
  const double apply_s = seconds_since(applying);
  EXPECT_EQ(applied.object_ids_size(), kItems);
  const v1::Stats loaded_start = raw.stats(session);
  std::this_thread::sleep_for(seconds(static_cast<long>(soak_seconds(10.0))));
  const v1::Stats loaded = raw.stats(session);
  // One more is refused, naming the limit; nothing already there is lost.
  v1::CreateObjectRequest one_more;
  one_more.set_session_id(session.session_id());
  *one_more.mutable_object() = request.scene().objects(0);
  v1::ItemRef ref;
  const grpc::Status refused =
      raw.call(&v1::Haptic::Stub::CreateObject, one_more, ref, session.session_secret());
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << refused.error_message();
  EXPECT_EQ(raw.stats(session).objects(), static_cast<std::uint32_t>(kItems));
  const double rate = static_cast<double>(loaded.ticks() - loaded_start.ticks()) /
                      std::max(1e-9, loaded.window_s());
  std::printf("soak: %d spheres in one session: applied in %.2f s; loop %.1f Hz before, lateness "
              "p99 %.0f us before and %.0f us with them (p99.9 %.0f us), overruns %llu with them; "
              "the %d-th refused: %s\n",
              kItems, apply_s, before.achieved_rate_hz(), before.lateness_p99_us(),
              loaded.lateness_p99_us(), loaded.lateness_p999_us(),
              static_cast<unsigned long long>(loaded.overruns() - loaded_start.overruns()), kItems + 1,
              refused.error_message().c_str());
  (void)rate;
}

TEST(Soak, SigtermUnderLoadExitsCleanlyThroughTheRamp) {
  const std::string recording = (std::filesystem::temp_directory_path() /
                                 ("soak-sigterm-" + std::to_string(::getpid()) + ".hrec")).string();
  auto server = std::make_unique<test::ServerProcess>(
      real_time_config(R"("max_sessions_per_peer": 32)"), "--record=" + recording);
  ForceTrace trace;
  Client observer(test::config_for(*server, "observer"));
  trace.attach(observer);
  std::vector<std::unique_ptr<Client>> load;
  for (int i = 0; i < 16; ++i) load.push_back(std::make_unique<Client>(test::config_for(*server, "load")));
  WallClientProcess wall(server->address());
  ASSERT_TRUE(wall.wait_ready());
  ASSERT_TRUE(trace.wait_for([](double f) { return f > 2.0; }, 0.3, seconds(5)));
  const auto terminated = steady_clock::now();
  server->signal_stop();
  const int exit_code = server->wait();
  const double exit_ms = seconds_since(terminated) * 1e3;
  EXPECT_EQ(exit_code, 0);

  // The recording has every tick to the end: the force after the shutdown began.
  recording::RecordingReader reader(recording);
  v1::Record record;
  std::uint64_t shutdown_after = 0;
  bool shutting_down = false;
  double contact = 0.0, previous = -1.0, largest_step = 0.0, last = -1.0;
  std::uint64_t ramp_ticks = 0;
  while (reader.next(record)) {
    if (record.has_change() && record.change().has_shutdown()) {
      shutting_down = true;
      shutdown_after = record.change().after_tick();
    } else if (record.has_sample() && record.sample().port() == 0) {
      const v1::Vec3& f = record.sample().force();
      const double magnitude = std::sqrt(f.x() * f.x() + f.y() * f.y() + f.z() * f.z());
      if (!shutting_down || record.sample().tick() <= shutdown_after) {
        contact = magnitude;
      } else {
        if (previous >= 0.0) largest_step = std::max(largest_step, std::abs(magnitude - previous));
        if (magnitude > 0.0) ++ramp_ticks;
      }
      previous = magnitude;
      last = magnitude;
    }
  }
  EXPECT_EQ(reader.error(), "");
  std::filesystem::remove(recording);
  std::printf("soak: SIGTERM with 17 clients streaming and one in contact (%.2f N): exit %d in %.0f "
              "ms; the force ramped to zero over %llu ticks, largest step %.3f N, last %.3g N\n",
              contact, exit_code, exit_ms, static_cast<unsigned long long>(ramp_ticks), largest_step,
              last);
  EXPECT_TRUE(shutting_down);
  EXPECT_GT(contact, 2.0);
  EXPECT_GE(ramp_ticks, 40u);
  EXPECT_LE(largest_step, kMaxForceStepPerTick);
  EXPECT_EQ(last, 0.0);
}

TEST(Soak, SigkillAndRestartEveryClientComesBackWithItsWall) {
  constexpr int kClients = 8;
  auto first = std::make_unique<test::ServerProcess>(real_time_config({}, 1000));
  const std::uint16_t grpc_port = first->grpc_port();
  const std::uint16_t udp_port = first->udp_port();
  std::vector<std::unique_ptr<test::ConnectionLog>> logs;
  std::vector<std::unique_ptr<Client>> clients;
  std::vector<ObjectHandle> walls;
  for (int i = 0; i < kClients; ++i) {
    logs.push_back(std::make_unique<test::ConnectionLog>());
    clients.push_back(std::make_unique<Client>(test::config_for(*first, "survivor")));
    logs.back()->attach(*clients.back());
    walls.push_back(clients.back()->add_wall(WallSpec{{0, 0, -0.01 * i}, {0, 0, 1}, {500.0, 1.0}}));
  }
  ::kill(first->pid(), SIGKILL);
  EXPECT_EQ(first->wait(), 128 + SIGKILL);
  const auto killed = steady_clock::now();
  for (auto& log : logs) ASSERT_TRUE(log->wait(1, seconds(5))) << "no loss noticed";
  const double noticed_ms = seconds_since(killed) * 1e3;
  test::ServerProcess second(real_time_config({}, 1000), {}, 0, grpc_port, udp_port);
  double slowest_ms = 0.0;
  for (auto& log : logs) {
    const auto resumed = log->wait(2, seconds(10));
    ASSERT_TRUE(resumed) << "a client did not come back";
    EXPECT_EQ(resumed->first.state, ConnectionChange::State::kResumed);
    EXPECT_EQ(resumed->first.items_not_restored, 0u);
    slowest_ms = std::max(slowest_ms, std::chrono::duration<double, std::milli>(
                                          resumed->second - second.ready_at()).count());
  }
  const Stats stats = clients.front()->stats();
  std::printf("soak: SIGKILL of hapticd with %d clients: all noticed within %.0f ms; after a "
              "restart on the same ports all were back, each with its wall, %.0f ms after the new "
              "server was ready\n",
              kClients, noticed_ms, slowest_ms);
  EXPECT_EQ(stats.sessions, static_cast<std::uint32_t>(kClients));
  EXPECT_EQ(stats.objects, static_cast<std::uint32_t>(kClients));
}

}  // namespace
}  // namespace haptic
