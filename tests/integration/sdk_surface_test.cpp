// The parts of the public SDK the other integration tests leave alone, each against the real
// hapticd in lockstep and checked against closed forms: spring, capsule and linear fields; field
// updates; the state callback; close() and moving a Client; recorded pushes, sinusoidal targets and
// the grip presets; every Stats counter after a known sequence; and another user's items, which
// nothing a client can do through the SDK touches.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <haptic/haptic.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <condition_variable>
#include <cstdint>
#include <fstream>
#include <functional>
#include <memory>
#include <mutex>
#include <numbers>
#include <string>
#include <thread>
#include <type_traits>
#include <variant>
#include <vector>

#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"

namespace haptic {
namespace {

using test::config_for;
using test::step_and_get;

using std::chrono::milliseconds;
using std::chrono::seconds;

// The default simulated point mass (docs/devices.md): 10 g, 0.022 N·s/m, at (0, 0, 20 mm), 1 kHz.
constexpr double kDeviceMass = 0.01;      // Unit: kg.
constexpr double kDeviceDamping = 0.022;  // Unit: N·s/m.
constexpr double kPeriod = 0.001;         // Unit: s.
constexpr Vec3 kStart{0.0, 0.0, 0.02};    // Unit: m.
constexpr std::uint32_t kRampTicks = 50;  // a new item ramps in over 50 ms

/// Polls `done` until it holds or `timeout` passes; for counters the server or the SDK's receive
/// thread update asynchronously. Returns whether it held.
bool wait_until(const std::function<bool()>& done, milliseconds timeout = milliseconds(5000)) {
  const auto give_up = std::chrono::steady_clock::now() + timeout;
  while (!done()) {
    if (std::chrono::steady_clock::now() > give_up) return false;
    std::this_thread::sleep_for(milliseconds(2));
  }
  return true;
}

Vec3 operator+(const Vec3& a, const Vec3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Vec3 operator-(const Vec3& a, const Vec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3 operator*(double s, const Vec3& v) { return {s * v.x, s * v.y, s * v.z}; }
double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
double norm(const Vec3& v) { return std::sqrt(dot(v, v)); }

void expect_near(const Vec3& actual, const Vec3& expected, double tolerance, const char* what) {
  EXPECT_NEAR(actual.x, expected.x, tolerance) << what << ".x";
  EXPECT_NEAR(actual.y, expected.y, tolerance) << what << ".y";
  EXPECT_NEAR(actual.z, expected.z, tolerance) << what << ".z";
}

/// Solves A x = b (3×3, rows of A) by Cramer's rule.
Vec3 solve(const Vec3 (&a)[3], const Vec3& b) {
  const auto det = [](const Vec3& r0, const Vec3& r1, const Vec3& r2) {
    return r0.x * (r1.y * r2.z - r1.z * r2.y) - r0.y * (r1.x * r2.z - r1.z * r2.x) +
           r0.z * (r1.x * r2.y - r1.y * r2.x);
  };
  const double d = det(a[0], a[1], a[2]);
  const auto column = [&](int c) {
    Vec3 r[3] = {a[0], a[1], a[2]};
    const double bs[3] = {b.x, b.y, b.z};
    for (int i = 0; i < 3; ++i) (c == 0 ? r[i].x : c == 1 ? r[i].y : r[i].z) = bs[i];
    return det(r[0], r[1], r[2]) / d;
  };
  return {column(0), column(1), column(2)};
}

class SdkSurface : public ::testing::Test {
 protected:
  test::ServerProcess server_{test::lockstep_config()};
};

TEST_F(SdkSurface, ASpringFieldBalancesThePushWhereItsStiffnessSaysAndAnUpdateMovesTheBalance) {
  Client client(config_for(server_, "spring"));
  // F = −k (p − a) − b v against a 0.5 N push along +y: at rest p = a + F_push / k.
  const Vec3 push{0.0, 0.5, 0.0};  // Unit: N.
  const SpringFieldSpec first{.anchor = {0.01, 0.0, 0.02}, .stiffness = 200.0, .damping = 2.0};
  FieldHandle spring = client.add_spring_field(first);
  client.set_operator(OperatorInput::push(push));
  State s = step_and_get(client, 1500);
  expect_near(s.position, first.anchor + (1.0 / first.stiffness) * push, 1e-7, "first balance");
  expect_near(s.force, -1.0 * push, 1e-5, "first force");
  // Each sample's force is the spring law on that sample's own position and velocity.
  expect_near(s.force,
              -first.stiffness * (s.position - first.anchor) - first.damping * s.velocity, 1e-9,
              "spring law");

  // Stiffer and elsewhere: the balance moves to a' + F_push / k'.
  const SpringFieldSpec second{.anchor = {-0.01, 0.005, 0.015}, .stiffness = 400.0, .damping = 2.0};
  spring.update(second);
  s = step_and_get(client, 1500);
  expect_near(s.position, second.anchor + (1.0 / second.stiffness) * push, 1e-7, "second balance");
  expect_near(s.force,
              -second.stiffness * (s.position - second.anchor) - second.damping * s.velocity, 1e-9,
              "updated spring law");
  EXPECT_EQ(client.stats().fields, 1u);  // an update replaces, it does not add
}

TEST_F(SdkSurface, ACapsulePushesBackWithStiffnessTimesPenetrationAlongItsRadius) {
  Client client(config_for(server_, "capsule"));
  // A capsule lying along x (its z axis turned 90° about y), radius 10 mm, its top at z = 0
  // over the tool. Standing upright instead it would reach z = 30 mm and hold the tool inside.
  constexpr double kRadius = 0.01;     // Unit: m.
  constexpr double kK = 1000.0;        // Unit: N/m.
  constexpr double kB = 1.0;           // Unit: N·s/m.
  const double c45 = std::sqrt(0.5);  // cos 45° = sin 45°: a 90° turn about y
  auto capsule = client.add_capsule({.pose = {.position = {0.0, 0.0, -kRadius},
                                              .orientation = {c45, 0.0, c45, 0.0}},
                                     .radius = kRadius,
                                     .half_length = 0.03,
                                     .impedance = {.stiffness = kK, .damping = kB}});
  step_and_get(client, 2 * kRampTicks);
  client.set_operator(OperatorInput::push({0.0, 0.0, -2.0}));
  const State s = step_and_get(client, 3000);
  ASSERT_EQ(s.contact_count, 1u);
  // Penetration and normal from the axis (the line y = 0, z = −r under the tool).
  const Vec3 from_axis{0.0, s.position.y, s.position.z + kRadius};
  const double penetration = kRadius - norm(from_axis);
  const Vec3 n = (1.0 / norm(from_axis)) * from_axis;
  expect_near(s.force, (kK * penetration - kB * dot(s.velocity, n)) * n, 1e-9, "K d − B v·n");
  // At rest it carries the 2 N push at 2 mm, and the proxy sits on the surface.
  EXPECT_NEAR(penetration, 0.002, 1e-6);
  EXPECT_NEAR(s.force.z, 2.0, 1e-4);
  EXPECT_NEAR(norm(Vec3{0.0, s.proxy.y, s.proxy.z + kRadius}), kRadius, 1e-9);
}

TEST_F(SdkSurface, ALinearFieldExertsF0PlusKTimesTheOffsetInsideItsRadiusAndNothingOutside) {
  Client client(config_for(server_, "linear"));
  // K is not symmetric (K[0].y ≠ K[1].x), so rows swapped for columns would show.
  const LinearFieldSpec field{.origin = kStart,
                              .force = {0.2, -0.1, 0.05},
                              .jacobian = {{-60.0, 15.0, 0.0}, {-5.0, -90.0, 0.0}, {0.0, 0.0, -40.0}},
                              .radius = 0.05,
                              .fade_width = 0.01};
  const auto law = [&](const Vec3& p) {
    const Vec3 d = p - field.origin;
    return field.force + Vec3{dot(field.jacobian[0], d), dot(field.jacobian[1], d),
                              dot(field.jacobian[2], d)};
  };
  auto linear = client.add_field(field);
  // A hand (100 N/m, 3 N·s/m) pulls towards a point 12 mm from the origin, inside r − fade.
  constexpr double kHand = 100.0;  // Unit: N/m.
  const Vec3 target = field.origin + Vec3{0.01, 0.005, -0.005};
  client.set_operator(OperatorInput::follow(target, kHand, 3.0));
  step_and_get(client, kRampTicks + 1);
  // Every sample while the tool moves: F0 + K (p − origin), exactly.
  for (int k = 0; k < 20; ++k) {
    const State s = step_and_get(client, 1);
    ASSERT_LT(norm(s.position - field.origin), field.radius - field.fade_width);
    expect_near(s.force, law(s.position), 1e-9, "F0 + K (p - origin)");
  }
  // At rest the field balances the hand: F0 + K δ + K_h (target − origin − δ) = 0.
  const State rest = step_and_get(client, 1500);
  const Vec3 a[3] = {field.jacobian[0] - Vec3{kHand, 0, 0}, field.jacobian[1] - Vec3{0, kHand, 0},
                     field.jacobian[2] - Vec3{0, 0, kHand}};
  const Vec3 delta = solve(a, -1.0 * (field.force + kHand * (target - field.origin)));
  expect_near(rest.position, field.origin + delta, 1e-8, "balance");
  expect_near(rest.force, law(rest.position), 1e-9, "law at rest");
  // Pulled 80 mm away the tool leaves the radius, and the field exerts nothing at all.
  client.set_operator(OperatorInput::follow(field.origin + Vec3{0.08, 0.0, 0.0}, kHand, 3.0));
  const State outside = step_and_get(client, 1500);
  ASSERT_GT(norm(outside.position - field.origin), field.radius);
  EXPECT_EQ(outside.force, (Vec3{0.0, 0.0, 0.0}));
}

TEST_F(SdkSurface, OnStateSeesEachStreamedTickUntilClearedWithAnEmptyFunction) {
  ClientConfig config = config_for(server_, "callback");
  config.state_decimation = 0;  // subscribed below, so that the stream's first tick is known
  Client client(config);
  std::mutex mutex;
  std::condition_variable arrived;
  std::vector<State> seen;
  client.on_state([&](const State& s) {
    std::lock_guard lock(mutex);
    seen.push_back(s);
    arrived.notify_all();
  });
  // A constant 10 mN push on the free tool from rest: m ẍ + b ẋ = F, which the plant solves
  // exactly, so x(t) = x0 + (F/b) (t − (m/b)(1 − e^{−b t / m})) at t = (tick − 1) ms.
  constexpr double kPush = 0.01;  // Unit: N.
  client.set_operator(OperatorInput::push({kPush, 0.0, 0.0}));
  const auto x_at = [&](std::uint64_t tick) {
    const double t = static_cast<double>(tick - 1) * kPeriod;
    const double tau = kDeviceMass / kDeviceDamping;
    return (kPush / kDeviceDamping) * (t - tau * (1.0 - std::exp(-t / tau)));
  };
  constexpr std::uint64_t kDecimation = 5;
  client.step(7);                 // ticks 1..7, before any subscription
  client.subscribe(kDecimation);  // the stream starts at tick 8: ticks 10, 15, ..., 105 are due
  // Each step brings one due sample, and the next waits until the callback has had it, so no
  // two queue up (the receive thread would hand out only the newer).
  std::vector<std::uint64_t> due;
  for (std::uint64_t tick = 10; tick <= 105; tick += kDecimation) {
    due.push_back(tick);
    const std::uint64_t stepped = client.step(tick == 10 ? 3 : 5);
    ASSERT_EQ(stepped, tick);
    std::unique_lock lock(mutex);
    ASSERT_TRUE(arrived.wait_for(lock, seconds(5), [&] { return !seen.empty() && seen.back().tick == tick; }))
        << "no callback for tick " << tick;
  }
  std::vector<State> first_phase;
  {
    std::lock_guard lock(mutex);
    first_phase = seen;
  }
  ASSERT_EQ(first_phase.size(), due.size());
  for (std::size_t i = 0; i < first_phase.size(); ++i) {
    const State& s = first_phase[i];
    EXPECT_EQ(s.tick, due[i]);
    EXPECT_EQ(s.sequence, i + 1);  // the session's datagrams, numbered from 1
    EXPECT_NEAR(s.server_time, static_cast<double>(s.tick - 1) * kPeriod, 1e-12);
    EXPECT_NEAR(s.position.x, x_at(s.tick), 1e-10) << "tick " << s.tick;
    EXPECT_EQ(s.position.y, 0.0);
    EXPECT_EQ(s.position.z, kStart.z);
  }
  const ReceiveCounters counters = client.receive_counters();
  EXPECT_EQ(counters.accepted, due.size());
  EXPECT_EQ(counters.skipped, 0u);
  EXPECT_EQ(counters.rejected, 0u);

  // Cleared: the next 20 samples arrive (the counters see them) but the old callback sees none.
  client.on_state({});
  client.step(100);  // ticks 106..205: due 110, ..., 205
  ASSERT_TRUE(wait_until([&] { return client.receive_counters().accepted == 40; }))
      << client.receive_counters().accepted;
  {
    std::lock_guard lock(mutex);
    EXPECT_EQ(seen.size(), first_phase.size());
  }
  // A new callback takes over with the next sample.
  std::uint64_t newest = 0;
  client.on_state([&](const State& s) {
    std::lock_guard lock(mutex);
    newest = s.tick;
    arrived.notify_all();
  });
  client.step(5);  // ticks 206..210
  std::unique_lock lock(mutex);
  EXPECT_TRUE(arrived.wait_for(lock, seconds(5), [&] { return newest == 210; })) << newest;
  EXPECT_EQ(seen.size(), first_phase.size());
}

/// Collects what on_event delivers, for a test to wait on.
class EventLog {
 public:
  std::function<void(const Event&)> sink() {
    return [this](const Event& event) {
      std::lock_guard lock(mutex_);
      events_.push_back(event);
      changed_.notify_all();
    };
  }
  /// Waits (at most 5 s) until an event of `kind` about `session` has arrived; false if none did.
  bool wait_for(Event::Kind kind, std::uint64_t session) {
    std::unique_lock lock(mutex_);
    return changed_.wait_for(lock, std::chrono::seconds(5),
                             [&] { return count_locked(kind, session) > 0; });
  }
  std::size_t count(Event::Kind kind, std::uint64_t session) const {
    std::lock_guard lock(mutex_);
    return count_locked(kind, session);
  }
  std::vector<Event> snapshot() {
    std::lock_guard lock(mutex_);
    return events_;
  }

 private:
  std::size_t count_locked(Event::Kind kind, std::uint64_t session) const {
    return static_cast<std::size_t>(std::count_if(events_.begin(), events_.end(), [&](const Event& e) {
      return e.kind == kind && e.session_id == session;
    }));
  }

  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<Event> events_;
};

TEST_F(SdkSurface, OnEventReportsOtherSessionsComingAndGoingUntilStopped) {
  EventLog log;  // outlives the client whose thread calls into it
  Client watcher(config_for(server_, "watcher"));
  watcher.on_event(log.sink());
  std::uint64_t other_id = 0;
  {
    Client other(config_for(server_, "other"));
    other_id = other.session_id();
    EXPECT_TRUE(log.wait_for(Event::Kind::kSessionOpened, other_id));
  }  // closed as it goes out of scope
  EXPECT_TRUE(log.wait_for(Event::Kind::kSessionClosed, other_id));
  const std::vector<Event> events = log.snapshot();
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.front().kind, Event::Kind::kWatchStarted);  // the stream's first, always
  EXPECT_FALSE(events.back().message.empty());
  // Stopped: nothing more arrives (a session opened and closed after it shows up nowhere).
  watcher.on_event({});
  std::uint64_t later_id = 0;
  {
    Client later(config_for(server_, "later"));
    later_id = later.session_id();
  }
  EventLog probe_log;
  Client probe(config_for(server_, "probe"));  // a second watcher proves the events happened
  probe.on_event(probe_log.sink());
  {
    Client last(config_for(server_, "last"));
    EXPECT_TRUE(probe_log.wait_for(Event::Kind::kSessionOpened, last.session_id()));
  }
  EXPECT_EQ(log.count(Event::Kind::kSessionOpened, later_id), 0u);
  EXPECT_EQ(log.snapshot().size(), events.size());
}

TEST(SdkEvents, OnEventBeyondTheServersStreamLimitIsRefusedNamingItAndTheOthersGoOn) {
  test::ServerProcess server(
      test::lockstep_config(R"("max_event_streams": 3, "max_event_streams_per_session": 1,
                               "max_event_streams_per_peer": 3)"));  // every client is on this host
  EventLog log;  // outlives the clients whose threads call into it
  std::vector<std::unique_ptr<Client>> clients;
  for (int i = 0; i < 3; ++i) {
    clients.push_back(std::make_unique<Client>(config_for(server, "watcher")));
    clients.back()->on_event(log.sink());
  }
  Client fourth(config_for(server, "fourth"));
  try {
    fourth.on_event(log.sink());
    ADD_FAILURE() << "a fourth stream was accepted past max_event_streams 3";
  } catch (const ResourceExhaustedError& error) {
    EXPECT_NE(std::string(error.what()).find("max_event_streams"), std::string::npos) << error.what();
  }
  // The three streams still deliver: each sees a new session open.
  Client newcomer(config_for(server, "newcomer"));
  EXPECT_TRUE(log.wait_for(Event::Kind::kSessionOpened, newcomer.session_id()));
  for (int attempt = 0; attempt < 500 && log.count(Event::Kind::kSessionOpened, newcomer.session_id()) < 3;
       ++attempt) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(log.count(Event::Kind::kSessionOpened, newcomer.session_id()), 3u);
}

// Every kind can replace an item in place through its handle: a box grown by 1 mm pushes with K
// times the new penetration, a box turned into a capsule pushes along the capsule's radius, and a
// viscous field turned into a linear one exerts its constant force.
TEST_F(SdkSurface, EveryObjectAndFieldKindCanReplaceAnItemThroughItsHandle) {
  Client client(config_for(server_, "update"));
  constexpr double kWall = 1000.0;  // Unit: N/m.
  client.set_operator(OperatorInput::follow(kStart, 2000.0, 20.0));  // holds the tool near kStart
  // The box's top face 1 mm above the tool.
  BoxSpec box{.pose = {.position = kStart - Vec3{0, 0, 0.009}},
              .half_extents = {0.05, 0.05, 0.01},
              .impedance = {kWall, 0.0}};
  auto handle = client.add_box(box);
  State s = step_and_get(client, 3 * kRampTicks);
  const auto top = [&](const BoxSpec& b) { return b.pose.position.z + b.half_extents.z; };
  EXPECT_EQ(s.contact_count, 1u);
  EXPECT_NEAR(s.force.z, kWall * (top(box) - s.position.z), 1e-9);
  box.half_extents.z = 0.011;  // 1 mm taller
  handle.update(box);
  s = step_and_get(client, 3 * kRampTicks);
  EXPECT_NEAR(s.force.z, kWall * (top(box) - s.position.z), 1e-9);
  EXPECT_NEAR(s.force.z, 2000.0 * kWall / (2000.0 + kWall) * 0.002, 1e-3);  // hand and wall in series
  // The same handle, now a capsule along z whose axis lies 10 mm along +x: 2 mm deep, pushing −x.
  const CapsuleSpec capsule{.pose = {.position = kStart + Vec3{0.01, 0, 0}},
                            .radius = 0.012,
                            .half_length = 0.02,
                            .impedance = {kWall, 0.0}};
  handle.update(capsule);
  s = step_and_get(client, 3 * kRampTicks);
  const Vec3 from_axis = s.position - Vec3{capsule.pose.position.x, capsule.pose.position.y, s.position.z};
  const double depth = capsule.radius - norm(from_axis);
  ASSERT_GT(depth, 0.0);
  expect_near(s.force, kWall * depth * (1.0 / norm(from_axis)) * from_axis, 1e-9, "capsule");
  EXPECT_LT(s.force.x, -1.0);
  handle.remove();
  // A viscous field replaced by a constant linear one: F = F0 wherever the tool is.
  auto field = client.add_field(ViscousFieldSpec{.damping = 0.5});
  step_and_get(client, 3 * kRampTicks);
  field.update(LinearFieldSpec{.origin = kStart, .force = {0.3, -0.2, 0.1}, .radius = 1.0, .fade_width = 0.1});
  s = step_and_get(client, 3 * kRampTicks);
  EXPECT_EQ(s.contact_count, 0u);
  expect_near(s.force, Vec3{0.3, -0.2, 0.1}, 1e-12, "F0");
}

/// One object and one field of every kind, each valid and out of the tool's way.
SceneSpec every_kind_scene() {
  SceneSpec scene;
  scene.objects = {
      WallSpec{.point = {0, 0, -0.05}, .normal = {0, 0, 1}, .impedance = {500.0, 1.0}},
      SphereSpec{.center = {0.1, 0, 0}, .radius = 0.01, .impedance = {500.0, 1.0}},
      BoxSpec{.pose = {.position = {0, 0.1, 0}}, .half_extents = {0.01, 0.01, 0.01}, .impedance = {500.0, 1.0}},
      CapsuleSpec{.pose = {.position = {0, -0.1, 0}}, .radius = 0.01, .half_length = 0.02,
                  .impedance = {500.0, 1.0}},
      TangentPlaneSpec{.pose = {.position = {0, 0, -0.06}}, .normal = {0, 0, 1},
                       .impedance = {.stiffness = 500.0, .damping = 1.0}},
      MeshSpec{.pose = {.position = {0, 0, -0.07}},
               .vertices = {{-0.05, -0.05, 0}, {0.05, -0.05, 0}, {0.05, 0.05, 0}, {-0.05, 0.05, 0}},
               .indices = {0, 1, 2, 0, 2, 3},
               .impedance = {.stiffness = 500.0, .damping = 1.0}}};
  scene.fields = {
      SpringFieldSpec{.anchor = kStart, .stiffness = 10.0, .damping = 0.1},
      DistanceSpringSpec{.anchor = {.kind = Distance::Kind::kPlane, .origin = {0, 0, 0.02}, .axis = {0, 0, 1}},
                         .stiffness = 5.0},
      PotentialFieldSpec{.distance = {.kind = Distance::Kind::kPoint, .origin = {0.2, 0, 0}},
                         .order = 2, .gain = 0.5, .offset = 0.01},
      LinearFieldSpec{.origin = kStart, .radius = 0.05, .fade_width = 0.01},
      ViscousFieldSpec{.damping = 0.1},
      DetentFieldSpec{.distance = {.kind = Distance::Kind::kPoint, .origin = {-0.2, 0, 0}},
                      .depth = 0.001, .radius = 0.02, .rim_height = 0.0002, .rim_width = 0.005}};
  return scene;
}

// apply_scene takes every object and field kind, all or nothing: the handles come back in the
// scene's order and each is its item (the energy report lists exactly their ids); a scene with one
// bad element is refused naming it and leaves the scene applied before untouched.
TEST_F(SdkSurface, ApplySceneTakesEveryKindAllOrNothingNamingTheBadElement) {
  Client client(config_for(server_, "scene"));
  const SceneSpec scene = every_kind_scene();
  const AppliedScene applied = client.apply_scene(scene);
  ASSERT_EQ(applied.objects.size(), 6u);
  ASSERT_EQ(applied.fields.size(), 6u);
  EXPECT_EQ(client.last_scene_stability().size(), 6u);
  step_and_get(client, 2);
  const auto ids_now = [&] {
    std::vector<std::uint64_t> ids;
    for (const ItemEnergy& item : client.scene_energy()) {
      if (item.session_id == client.session_id()) ids.push_back(item.id);
    }
    std::sort(ids.begin(), ids.end());
    return ids;
  };
  std::vector<std::uint64_t> expected;
  for (const ObjectHandle& h : applied.objects) expected.push_back(h.id());
  for (const FieldHandle& h : applied.fields) expected.push_back(h.id());
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(ids_now(), expected);
  // The third object made bad: refused naming it, and the scene above stays.
  SceneSpec bad = scene;
  bad.objects[2] = BoxSpec{.half_extents = {0.01, 0.0, 0.01}, .impedance = {500.0, 1.0}};
  try {
    client.apply_scene(bad);
    ADD_FAILURE() << "a box with a zero half extent was accepted";
  } catch (const InvalidArgumentError& error) {
    EXPECT_EQ(std::string(error.what()).rfind("ApplyScene: scene.objects[2].box.half_extents.y: ", 0), 0u)
        << error.what();
  }
  step_and_get(client, 2);
  EXPECT_EQ(ids_now(), expected);
  // A client-side check names the element the same way.
  SceneSpec negative = scene;
  negative.objects[0] = WallSpec{.normal = {0, 0, 1}, .impedance = {-1.0, 0.0}};
  EXPECT_THROW(
      {
        try {
          client.apply_scene(negative);
        } catch (const InvalidArgumentError& error) {
          EXPECT_EQ(std::string(error.what()), "ApplyScene: scene.objects[0].impedance.stiffness: must be >= 0");
          throw;
        }
      },
      InvalidArgumentError);
}

// The scene reads back as it was given, item for item (every kind, an update, a removal), in id
// order with owners; another session's items only when asked for every session's; and what is
// read back, applied by another client, makes the same scene.
TEST(SdkScene, TheSceneReadsBackAsGivenInIdOrderWithOwnersAndWithoutRemovedItems) {
  // The server's own scene: a floor turned 90 degrees about x, so its normal points along -y.
  test::ServerProcess server(test::lockstep_config(R"("initial_scene": {"objects": [{
      "pose": {"position": {"z": -0.5}, "orientation": {"w": 0.7071067811865476, "x": 0.7071067811865476}},
      "impedance": {"stiffness": 100}, "half_space": {"normal": {"z": 1}}}]})"));
  Client client(config_for(server, "reader"));
  const SceneSpec scene = every_kind_scene();
  AppliedScene applied = client.apply_scene(scene);
  RegisteredScene read = client.scene();
  EXPECT_EQ(read.scene.objects, scene.objects);
  EXPECT_EQ(read.scene.fields, scene.fields);
  for (std::size_t i = 0; i < applied.objects.size(); ++i) EXPECT_EQ(read.object_ids[i], applied.objects[i].id());
  for (std::size_t i = 0; i < applied.fields.size(); ++i) EXPECT_EQ(read.field_ids[i], applied.fields[i].id());
  EXPECT_EQ(read.object_sessions, std::vector<std::uint64_t>(6, client.session_id()));

  // An update keeps its place (its id), a removed field is gone at once (though ramping out), a
  // new wall comes last.
  const SphereSpec moved{.center = {0.12, 0, 0}, .radius = 0.015, .impedance = {600.0, 2.0}, .shared = true};
  applied.objects[1].update(moved);
  applied.fields[0].remove();
  const WallSpec extra{.point = {0, 0, -0.08}, .normal = {0, 1, 1}, .impedance = {700.0, 1.0}};
  ObjectHandle extra_handle = client.add_wall(extra);
  read = client.scene();
  SceneSpec expected = scene;
  expected.objects[1] = moved;
  expected.objects.push_back(extra);
  expected.fields.erase(expected.fields.begin());
  EXPECT_EQ(read.scene.objects, expected.objects);
  EXPECT_EQ(read.scene.fields, expected.fields);
  EXPECT_EQ(read.object_ids[1], applied.objects[1].id());
  EXPECT_EQ(read.object_ids.back(), extra_handle.id());

  // Another session's items are its own; every session's shows them all with their owners,
  // the server's initial scene (session 0) first, its pose folded into the wall's normal.
  Client other(config_for(server, "other"));
  ObjectHandle theirs = other.add_wall({.point = {0, 0, -0.09}, .normal = {0, 0, 1}, .impedance = {800.0, 1.0}});
  EXPECT_EQ(client.scene().scene.objects.size(), 7u);
  const RegisteredScene everything = other.scene(true);
  ASSERT_EQ(everything.scene.objects.size(), 9u);
  EXPECT_EQ(everything.object_sessions.front(), 0u);
  const auto* floor = std::get_if<WallSpec>(&everything.scene.objects.front());
  ASSERT_NE(floor, nullptr);
  EXPECT_NEAR(floor->normal.x, 0.0, 1e-12);
  EXPECT_NEAR(floor->normal.y, -1.0, 1e-12);
  EXPECT_NEAR(floor->normal.z, 0.0, 1e-12);
  EXPECT_EQ(everything.object_sessions.back(), other.session_id());
  EXPECT_EQ(everything.object_ids.back(), theirs.id());
  EXPECT_TRUE(std::is_sorted(everything.object_ids.begin(), everything.object_ids.end()));
  EXPECT_EQ(std::count(everything.object_sessions.begin(), everything.object_sessions.end(), client.session_id()), 7);
  EXPECT_EQ(everything.field_sessions, std::vector<std::uint64_t>(5, client.session_id()));

  // Read back and applied by a third client: the same scene.
  Client copy(config_for(server, "copy"));
  const AppliedScene copied = copy.apply_scene(client.scene().scene);
  EXPECT_EQ(copied.objects.size(), 7u);
  EXPECT_EQ(copy.scene().scene.objects, client.scene().scene.objects);
  EXPECT_EQ(copy.scene().scene.fields, client.scene().scene.fields);
}

// A callback that takes far longer than the lease does not lose the session: it runs on a thread
// of its own while the receive thread goes on heartbeating, and the samples it was too busy to
// see are counted. (On the receive thread, as before, this session's lease ran out.)
TEST(SdkCallback, ASlowStateCallbackDoesNotLoseTheLeaseAndItsMissedSamplesAreCounted) {
  test::ServerProcess server(test::lockstep_config(R"("lease_timeout_ms": 300)"));
  Client client(config_for(server, "slow"));
  std::mutex mutex;
  std::condition_variable changed;
  int calls = 0;
  bool release = false;
  client.on_state([&](const State&) {
    std::unique_lock lock(mutex);
    ++calls;
    changed.notify_all();
    // The first call blocks for 1 s, more than three leases.
    if (calls == 1) changed.wait_for(lock, seconds(1), [&] { return release; });
  });
  client.step(1);
  {
    std::unique_lock lock(mutex);
    ASSERT_TRUE(changed.wait_for(lock, seconds(5), [&] { return calls == 1; }));
  }
  for (int i = 0; i < 5; ++i) {  // samples arrive while the callback is stuck
    client.step(1);
    std::this_thread::sleep_for(milliseconds(20));
  }
  std::this_thread::sleep_for(milliseconds(900));  // past 3 leases from the callback's start
  // The session is alive: calls work and the server has not expired it.
  EXPECT_NO_THROW(client.stats());
  EXPECT_EQ(client.stats().leases_expired, 0u);
  {
    std::unique_lock lock(mutex);
    release = true;
    changed.notify_all();
    ASSERT_TRUE(changed.wait_for(lock, seconds(5), [&] { return calls >= 2; }));  // the newest next
  }
  // 5 arrived while it was busy and the newest was handed on: 4 missed, counted where they were
  // passed over (by the callback's hand-off, or on the socket when two queued up together).
  const auto missed = [&] {
    const ReceiveCounters c = client.receive_counters();
    return c.callback_skipped + c.skipped;
  };
  ASSERT_TRUE(wait_until([&] { return missed() == 4; })) << missed();
  EXPECT_GE(client.receive_counters().callback_skipped, 1u);
  client.on_state({});
}

// The graphics helpers against the lockstep truth: the tool swings on a soft spring (ω = 10 rad/s)
// and every tick's sample is kept. Between samples h = 10 ms apart, Hermite interpolation is within
// its error bound h^4/384 max|d4x/dt4| = h^4/384 w^4 A (about 3 nm for the swing's amplitude
// A <= 11 mm) of the tick in the middle, where linear interpolation is off by um; predicting 5 ms
// past the newest sample with its acceleration beats holding its velocity.
TEST_F(SdkSurface, InterpolationAndPredictionMatchTheLockstepTruth) {
  Client client(config_for(server_, "graphics"));
  auto spring = client.add_spring_field({.anchor = kStart + Vec3{0.01, 0.0, 0.005}, .stiffness = 1.0});
  std::vector<State> truth;
  for (int k = 0; k < 200; ++k) truth.push_back(step_and_get(client, 1));
  double worst_hermite = 0.0, worst_linear = 0.0, worst_predicted = 0.0, worst_held = 0.0;
  for (std::size_t k = 100; k + 10 < truth.size(); k += 7) {  // after the spring's ramp-in
    const State& a = truth[k];
    const State& b = truth[k + 10];
    const State& middle = truth[k + 5];
    worst_hermite = std::max(worst_hermite,
                             norm(interpolate_position(a, b, middle.server_time) - middle.position));
    worst_linear = std::max(worst_linear, norm(0.5 * (a.position + b.position) - middle.position));
    const State& ahead = truth[k + 5];  // 5 ms past truth[k]
    worst_predicted = std::max(
        worst_predicted, norm(predict_position(truth[k - 1], a, ahead.server_time) - ahead.position));
    worst_held = std::max(worst_held, norm(a.position + 0.005 * a.velocity - ahead.position));
  }
  std::printf("  interpolation: Hermite %.3g m, linear %.3g m; 5 ms ahead: predicted %.3g m, "
              "constant velocity %.3g m\n",
              worst_hermite, worst_linear, worst_predicted, worst_held);
  EXPECT_GT(worst_linear, 1e-6);  // the motion really curves
  const double h = 0.01, omega = 10.0, amplitude = norm(Vec3{0.01, 0.0, 0.005});
  EXPECT_LT(worst_hermite, std::pow(h, 4) / 384.0 * std::pow(omega, 4) * amplitude);
  EXPECT_LT(worst_hermite, 1e-3 * worst_linear);
  EXPECT_LT(worst_predicted, 0.2 * worst_held);
  // Equal times: no division by zero.
  EXPECT_EQ(interpolate_position(truth[5], truth[5], truth[5].server_time), truth[5].position);
  const Vec3 held = predict_position(truth[5], truth[5], truth[5].server_time + 0.001);
  expect_near(held, truth[5].position + 0.001 * truth[5].velocity, 1e-15, "same sample");
}

TEST_F(SdkSurface, CloseEndsTheSessionAndLeavesItsHandlesInert) {
  Client watcher(config_for(server_, "watcher"));
  Client closing(config_for(server_, "closing"));
  auto floor = closing.add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1}, .impedance = {1000.0, 1.0}});
  auto spring = closing.add_spring_field({.anchor = {0.0, 0.0, 0.0}, .stiffness = 10.0, .damping = 0.1});
  watcher.set_operator(OperatorInput::push({0, 0, -2.0}));
  // The floor and the spring (anchored on the floor, pulling up) share the 2 N push:
  // 1000 d + 10 d = 2 N.
  const State pressed = step_and_get(watcher, 3000);
  EXPECT_NEAR(pressed.position.z, -2.0 / 1010.0, 1e-6);
  EXPECT_NEAR(pressed.force.z, 2.0, 1e-4);
  Stats before = watcher.stats();
  EXPECT_EQ(before.sessions, 2u);
  EXPECT_EQ(before.objects, 1u);
  EXPECT_EQ(before.fields, 1u);

  closing.close();
  const Stats after = watcher.stats();
  EXPECT_EQ(after.sessions, before.sessions - 1);
  EXPECT_EQ(after.objects, 0u);  // the session's items are fading out: no longer counted
  EXPECT_EQ(after.fields, 0u);
  // The handles outlive their session: remove() does nothing (no call, so no NotFoundError) ...
  EXPECT_TRUE(floor.owned());
  EXPECT_NO_THROW(floor.remove());
  EXPECT_FALSE(floor.owned());
  // ... and anything that needs the session says the Client is closed.
  EXPECT_THROW(spring.update({.anchor = {0, 0, 0.01}, .stiffness = 10.0}), Error);
  EXPECT_THROW(closing.step(1), Error);
  EXPECT_THROW(closing.stats(), Error);
  EXPECT_THROW(closing.add_wall({.normal = {0, 0, 1}, .impedance = {1000.0, 1.0}}), Error);
  EXPECT_NO_THROW(closing.close());  // twice is harmless
  EXPECT_EQ(watcher.stats().sessions, 1u);
  // With the floor gone (ramped out over 50 ms) the push meets nothing.
  const State gone = step_and_get(watcher, kRampTicks + 1);
  EXPECT_EQ(gone.force, (Vec3{0.0, 0.0, 0.0}));
  EXPECT_EQ(gone.contact_count, 0u);
}

TEST_F(SdkSurface, AMovedClientKeepsTheSessionAndItsHandlesAndTheMovedFromOneThrows) {
  Client original(config_for(server_, "original"));
  const std::uint64_t session = original.session_id();
  auto floor = original.add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1}, .impedance = {1000.0, 1.0}});

  Client moved(std::move(original));
  EXPECT_EQ(moved.session_id(), session);
  EXPECT_THROW(original.session_id(), Error);  // NOLINT(bugprone-use-after-move): the point
  EXPECT_THROW(original.step(1), Error);
  EXPECT_THROW(original.add_wall({.normal = {0, 0, 1}, .impedance = {1000.0, 1.0}}), Error);
  moved.set_operator(OperatorInput::push({0, 0, -2.0}));
  EXPECT_NEAR(step_and_get(moved, 3000).position.z, -0.002, 1e-6);
  // The handle made through the old object acts for the session, wherever its Client now lives.
  floor.update(WallSpec{.point = {0, 0, 0.001}, .normal = {0, 0, 1}, .impedance = {1000.0, 1.0}});
  EXPECT_NEAR(step_and_get(moved, 3000).position.z, 0.001 - 0.002, 1e-6);

  // Move assignment: the target's own session closes, and it takes over the moved one.
  Client target(config_for(server_, "target"));
  auto far_wall = target.add_wall({.point = {0, 0, -0.5}, .normal = {0, 0, 1}, .impedance = {1000.0, 1.0}});
  EXPECT_EQ(moved.stats().sessions, 2u);
  EXPECT_EQ(moved.stats().objects, 2u);
  target = std::move(moved);
  EXPECT_EQ(target.session_id(), session);
  EXPECT_THROW(moved.stats(), Error);  // NOLINT(bugprone-use-after-move)
  const Stats stats = target.stats();
  EXPECT_EQ(stats.sessions, 1u);
  EXPECT_EQ(stats.objects, 1u);
  EXPECT_NO_THROW(far_wall.remove());  // its Client's session is gone: nothing to do
  // The floor is still this session's and still carries the push 2 mm into it.
  EXPECT_NEAR(step_and_get(target, 100).position.z, 0.001 - 0.002, 1e-6);
  floor.remove();
  EXPECT_EQ(target.stats().objects, 0u);
}

TEST_F(SdkSurface, ARecordedPushIsPlayedBackInterpolatedBetweenItsSamplesAgainstAWall) {
  Client client(config_for(server_, "recorded"));
  constexpr double kK = 1000.0;  // Unit: N/m.
  auto floor = client.add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1}, .impedance = {kK, 1.0}});
  client.set_operator(OperatorInput::push({0, 0, -1.0}));
  std::uint64_t now = step_and_get(client, 1500).tick;
  // The sample of tick `from` + 1 + j was read after j ms of an input set after tick `from`.
  const auto at = [&](std::uint64_t from, double t_s) {
    const std::uint64_t want = from + 1 + static_cast<std::uint64_t>(std::llround(t_s / kPeriod));
    const State s = step_and_get(client, static_cast<std::uint32_t>(want - now));
    now = s.tick;
    EXPECT_EQ(s.tick, want);
    return s;
  };
  // −1, −3, −2 N one every 200 ms, linear in between, then held. The 10 g tool on the wall
  // (ω0 ≈ 316 rad/s) follows quasi-statically: the floor's force is the push to within 10 mN
  // (the contact rounds each corner of the profile by a few mN); holding it or jumping between
  // samples would be 0.5 N off or more.
  client.set_operator(OperatorInput::push_recorded({{0, 0, -1.0}, {0, 0, -3.0}, {0, 0, -2.0}}, 0.2));
  const std::uint64_t first = now;
  EXPECT_NEAR(at(first, 0.1).force.z, 2.0, 1e-2);  // half way from 1 to 3 N
  EXPECT_NEAR(at(first, 0.2).force.z, 3.0, 1e-2);
  EXPECT_NEAR(at(first, 0.3).force.z, 2.5, 1e-2);  // half way from 3 back to 2 N
  const State held = at(first, 1.5);               // after the last sample, it holds
  EXPECT_NEAR(held.force.z, 2.0, 1e-5);
  EXPECT_NEAR(held.position.z, -2.0 / kK, 1e-8);

  // Repeating, it wraps round: −1, −3, back to −1 at 400 ms, and on.
  client.set_operator(OperatorInput::push_recorded({{0, 0, -1.0}, {0, 0, -3.0}}, 0.2, true));
  const std::uint64_t second = now;
  EXPECT_NEAR(at(second, 0.3).force.z, 2.0, 1e-2);  // half way from 3 back to 1 N
  EXPECT_NEAR(at(second, 0.4).force.z, 1.0, 1e-2);  // the first sample again
  EXPECT_NEAR(at(second, 0.5).force.z, 2.0, 1e-2);
  EXPECT_NEAR(at(second, 0.6).force.z, 3.0, 1e-2);
}

TEST_F(SdkSurface, ASineTargetIsTrackedAsTheCustomGripsSteadyStateResponseSays) {
  Client client(config_for(server_, "sine"));
  // A custom grip: 0.5 kg of hand on the 10 g tool, 400 N/m, 10 N·s/m, its target swinging
  // x_t = T + A sin(2π f t). With M = m_h + m and F = K_h (x_t − x) + B_h (ẋ_t − ẋ):
  //   M ẍ + (B_h + b) ẋ + K_h x = K_h x_t + B_h ẋ_t,
  //   H(jω) = (K_h + jω B_h) / (K_h − M ω² + jω (B_h + b)),
  // so once the start has died away (rate (B_h + b) / 2M ≈ 9.8 1/s) x = T + A |H| sin(ωt + ∠H):
  // 22 % more than the target's swing and 71 mrad behind it, for the hand's mass.
  constexpr double kHandMass = 0.5;        // Unit: kg.
  constexpr double kHandStiffness = 400.0; // Unit: N/m.
  constexpr double kHandDamping = 10.0;    // Unit: N·s/m.
  constexpr double kFrequency = 2.0;       // Unit: Hz.
  const Vec3 amplitude{0.01, 0.0, 0.005};  // Unit: m.
  OperatorInput input;
  input.mode = OperatorInput::Mode::kFollow;
  input.grip = OperatorInput::Grip::kCustom;
  input.target = kStart;
  input.mass = kHandMass;
  input.stiffness = kHandStiffness;
  input.damping = kHandDamping;
  input.path.shape = OperatorInput::Path::Shape::kSine;
  input.path.amplitude = amplitude;
  input.path.frequency_hz = kFrequency;
  const std::uint64_t from = step_and_get(client, 1).tick;  // t = 0 at tick from + 1
  client.set_operator(input);

  const double w = 2.0 * std::numbers::pi * kFrequency;
  const std::complex<double> h =
      std::complex<double>(kHandStiffness, w * kHandDamping) /
      std::complex<double>(kHandStiffness - (kHandMass + kDeviceMass) * w * w,
                           w * (kHandDamping + kDeviceDamping));
  ASSERT_NEAR(std::abs(h), 1.221, 1e-3);
  std::uint64_t now = from;
  for (int k = 0; k < 12; ++k) {
    const std::uint64_t want = from + 1500 + 37 * static_cast<std::uint64_t>(k);  // spread over a period
    const State s = step_and_get(client, static_cast<std::uint32_t>(want - now));
    now = s.tick;
    const double t = static_cast<double>(s.tick - from - 1) * kPeriod;
    const Vec3 expected = kStart + (std::abs(h) * std::sin(w * t + std::arg(h))) * amplitude;
    expect_near(s.position, expected, 1e-5, "steady-state swing");  // a 1 ms slip: 0.15 mm
  }
}

TEST_F(SdkSurface, LooseAndCustomGripsSettleAwayFromTheirTargetsByFieldForceOverGripStiffness) {
  Client client(config_for(server_, "grips"));
  // A damped 100 N/m spring holds the tool at the start; the hand pulls it towards its target.
  // At rest k (a − p) + K_h (T − p) = 0: p = (k a + K_h T) / (k + K_h), and the field's force
  // F = k (a − p) leaves the tool F / K_h short of the target.
  const SpringFieldSpec spring{.anchor = kStart, .stiffness = 100.0, .damping = 2.0};
  auto field = client.add_spring_field(spring);
  const auto balance = [&](const Vec3& target, double grip_stiffness) {
    return (1.0 / (spring.stiffness + grip_stiffness)) *
           (spring.stiffness * spring.anchor + grip_stiffness * target);
  };

  // Loose (0.2 kg, 2 N/m, 3 N·s/m): the input's own stiffness and damping do not count.
  const Vec3 loose_target = kStart + Vec3{0.04, 0.0, 0.0};
  OperatorInput loose = OperatorInput::follow(loose_target, 0.0, 0.0);
  loose.grip = OperatorInput::Grip::kLoose;
  client.set_operator(loose);
  State s = step_and_get(client, 1500);
  constexpr double kLooseStiffness = 2.0;  // Unit: N/m.
  expect_near(s.position, balance(loose_target, kLooseStiffness), 1e-9, "loose balance");
  expect_near(s.position - loose_target, (1.0 / kLooseStiffness) * s.force, 1e-8, "loose offset");
  EXPECT_NEAR(s.force.x,
              -spring.stiffness * 0.04 * kLooseStiffness / (spring.stiffness + kLooseStiffness), 1e-8);

  // Custom: as given (0.1 kg, 300 N/m, 5 N·s/m).
  constexpr double kCustomStiffness = 300.0;  // Unit: N/m.
  const Vec3 custom_target = kStart + Vec3{0.0, -0.02, 0.01};
  OperatorInput custom = OperatorInput::follow(custom_target, kCustomStiffness, 5.0);
  custom.mass = 0.1;
  client.set_operator(custom);
  s = step_and_get(client, 1500);
  expect_near(s.position, balance(custom_target, kCustomStiffness), 1e-9, "custom balance");
  expect_near(s.position - custom_target, (1.0 / kCustomStiffness) * s.force, 1e-8, "custom offset");
}

/// Sends `count` datagrams of zeros to the server's UDP port: not even a header.
void send_junk(std::uint16_t port, int count) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(fd, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(port);
  ::inet_pton(AF_INET, "127.0.0.1", &to.sin_addr);
  const std::uint8_t junk[16] = {};
  for (int i = 0; i < count; ++i) {
    EXPECT_EQ(::sendto(fd, junk, sizeof junk, 0, reinterpret_cast<const sockaddr*>(&to), sizeof to),
              static_cast<ssize_t>(sizeof junk));
  }
  ::close(fd);
}

TEST(SdkStats, EveryCounterMatchesWhatAKnownLockstepSequenceImplies) {
  test::ServerProcess server(test::lockstep_config(R"("lease_timeout_ms": 1000)"));
  // Quiet clients: one heartbeat when they open (answered by one path response, after one
  // challenge) and no periodic ones, no stream until asked: every datagram is accounted for.
  // Their leases are kept by their calls.
  const auto quiet = [&](const char* name) {
    ClientConfig config = config_for(server, name);
    config.state_decimation = 0;
    config.heartbeat_period = std::chrono::hours(1);
    config.reconnect = false;  // a supervising client probes a quiet connection: not silent
    return config;
  };
  Client a(quiet("stats-a"));
  Client b(quiet("stats-b"));
  auto lapsing = std::make_unique<Client>(quiet("stats-lapsing"));  // silent from here on
  constexpr std::uint64_t kJunk = 5;
  send_junk(server.udp_port(), static_cast<int>(kJunk));
  const auto poll = [&] {  // a call from each renews both leases
    b.stats();
    return a.stats();
  };
  ASSERT_TRUE(wait_until([&] {
    const Stats s = poll();
    return s.datagrams_received >= 6 && s.datagrams_dropped >= kJunk;
  }));

  constexpr std::uint64_t kDecimationA = 4;
  constexpr std::uint64_t kDecimationB = 10;
  a.subscribe(kDecimationA);  // both from tick 1: nothing has run yet
  b.subscribe(kDecimationB);
  std::vector<ObjectHandle> walls;  // far below the tool: never touched
  for (int i = 0; i < 4; ++i) {
    walls.push_back(a.add_wall(
        {.point = {0, 0, -0.5 - 0.1 * i}, .normal = {0, 0, 1}, .impedance = {1000.0, 1.0}}));
  }
  walls.front().remove();
  // A spring 50 mm away at 1000 N/m against a hand holding the tool at 2000 N/m: once ramped in
  // it asks for 1000 × (50 − 10) mm = 40 N and more, and the device gives its 20 N, every tick.
  // Each Step reply's flags say which ticks were cut; the counter must agree.
  auto spring = b.add_spring_field({.anchor = {0.05, 0.0, 0.02}, .stiffness = 1000.0});
  a.set_operator(OperatorInput::follow(kStart, 2000.0, 50.0));
  constexpr std::uint64_t kTicks = 300;
  std::uint64_t saturated = 0;
  std::uint64_t saturated_after_ramp = 0;
  std::uint64_t faults = 0;
  State last;
  for (std::uint64_t k = 0; k < kTicks; ++k) {
    last = step_and_get(k % 2 == 0 ? a : b, 1);
    saturated += (last.flags & kForceSaturated) ? 1 : 0;
    saturated_after_ramp += (last.tick > kRampTicks && (last.flags & kForceSaturated)) ? 1 : 0;
    faults += (last.flags & kForceFault) ? 1 : 0;
  }
  ASSERT_EQ(last.tick, kTicks);
  EXPECT_EQ(saturated_after_ramp, kTicks - kRampTicks);
  EXPECT_NEAR(last.force.x, 20.0, 1e-9);  // the device's max_force, along the spring's pull

  const std::uint64_t due_a = kTicks / kDecimationA;
  const std::uint64_t due_b = kTicks / kDecimationB;
  ASSERT_TRUE(wait_until([&] {
    return a.receive_counters().accepted >= due_a && b.receive_counters().accepted >= due_b &&
           poll().datagrams_sent >= due_a + due_b;
  }));
  // The lapsing client has made no call and sent no heartbeat since it opened: its lease ends.
  ASSERT_TRUE(wait_until([&] { return poll().leases_expired >= 1; }));

  const Stats s = a.stats();
  EXPECT_EQ(s.ticks, kTicks);
  EXPECT_DOUBLE_EQ(s.achieved_rate_hz, 1000.0);  // ticks over server time, which is ticks × 1 ms
  // Lockstep waits for no deadline and stamps no real time: no lateness, no overruns, no delay.
  EXPECT_EQ(s.lateness_p50_us, 0.0);
  EXPECT_EQ(s.lateness_p99_us, 0.0);
  EXPECT_EQ(s.lateness_max_us, 0.0);
  EXPECT_EQ(s.overruns, 0u);
  EXPECT_EQ(s.send_delay_p50_us, 0.0);
  EXPECT_EQ(s.send_delay_p99_us, 0.0);
  EXPECT_EQ(s.sessions, 2u);
  EXPECT_EQ(s.objects, 3u);
  EXPECT_EQ(s.fields, 1u);
  // Every due tick sent (lockstep never conflates), and each one received.
  EXPECT_EQ(s.datagrams_sent, due_a + due_b);
  EXPECT_EQ(s.samples_skipped, 0u);
  EXPECT_EQ(a.receive_counters().accepted, due_a);
  EXPECT_EQ(b.receive_counters().accepted, due_b);
  // Three clients: a heartbeat and a path response each; the junk is dropped, nothing else.
  EXPECT_EQ(s.datagrams_received, 6u);
  EXPECT_EQ(s.path_challenges_sent, 3u);
  EXPECT_EQ(s.datagrams_dropped, kJunk);
  EXPECT_EQ(s.heartbeats_rate_limited, 0u);
  EXPECT_EQ(s.datagrams_foreign_source, 0u);
  EXPECT_EQ(s.force_saturations, saturated);
  EXPECT_EQ(s.force_faults, faults);
  EXPECT_EQ(faults, 0u);
  EXPECT_EQ(s.device_faults, 0u);
  EXPECT_EQ(s.passivity_active_ticks, 0u);  // it watches contacts, and there were none
  EXPECT_EQ(s.leases_expired, 1u);
  // One connection: the SDK's channels to one server share it (gRPC's subchannel pool).
  EXPECT_EQ(s.connections_open, 1u);
  EXPECT_EQ(s.connections_refused, 0u);
  lapsing.reset();  // closing a session that is gone does not throw
}

TEST_F(SdkSurface, AnotherUsersItemsSurviveEverythingTheSdkLetsAClientDo) {
  // The SDK names an item only through a handle it made from its own session's reply: nothing
  // turns an id read elsewhere into one.
  static_assert(!std::is_constructible_v<ObjectHandle, std::uint64_t>);
  static_assert(!std::is_constructible_v<FieldHandle, std::uint64_t>);
  static_assert(!std::is_constructible_v<ObjectHandle, Client&, std::uint64_t>);
  static_assert(!std::is_constructible_v<FieldHandle, Client&, std::uint64_t>);
  Client alice(config_for(server_, "alice"));
  Client bob(config_for(server_, "bob"));
  auto floor = alice.add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1}, .impedance = {1000.0, 1.0}});
  const Vec3 puck_at{0.05, 0.0, 0.05};  // a shared virtual mass, well away from the tool
  auto puck = alice.add_sphere({.center = puck_at, .radius = 0.01, .impedance = {1000.0, 2.0},
                                .dynamics = {.mass = 0.1, .damping = 4.0}, .shared = true});
  auto damper = alice.add_field(ViscousFieldSpec{.damping = 0.1});
  auto own = bob.add_wall({.point = {0, 0, -0.5}, .normal = {0, 0, 1}, .impedance = {1000.0, 1.0}});
  step_and_get(alice, 1);  // the loop adopts the scene these reports are read from

  // What Bob can learn: the puck and where it is, and every item with its owner.
  const std::vector<ObjectState> masses = bob.object_states();
  ASSERT_EQ(masses.size(), 1u);
  EXPECT_EQ(masses[0].id, puck.id());
  EXPECT_EQ(masses[0].position, puck_at);
  const auto owners = [&](Client& asking) {
    std::vector<std::pair<std::uint64_t, std::uint64_t>> out;  // (id, session)
    for (const ItemEnergy& e : asking.scene_energy()) out.emplace_back(e.id, e.session_id);
    std::sort(out.begin(), out.end());
    return out;
  };
  using Owned = std::vector<std::pair<std::uint64_t, std::uint64_t>>;
  Owned alices = {{floor.id(), alice.session_id()}, {puck.id(), alice.session_id()},
                  {damper.id(), alice.session_id()}};
  std::sort(alices.begin(), alices.end());
  Owned all = alices;
  const std::uint64_t own_id = own.id();
  all.emplace_back(own_id, bob.session_id());
  std::sort(all.begin(), all.end());
  EXPECT_EQ(owners(bob), all);

  // Everything Bob's SDK does to "the scene" is done to his session's part of it.
  bob.apply_scene({}, {}, {});
  EXPECT_NO_THROW(own.remove());  // replaced by apply_scene: nothing left to remove
  Stats stats = alice.stats();
  EXPECT_EQ(stats.objects, 2u);
  EXPECT_EQ(stats.fields, 1u);
  const std::string empty_scene = ::testing::TempDir() + "/sdk_surface_empty_scene.json";
  std::ofstream(empty_scene) << "{}";
  const Client::FileScene nothing = bob.apply_scene_file(empty_scene);
  EXPECT_TRUE(nothing.objects.empty());
  EXPECT_TRUE(nothing.fields.empty());
  bob.close();
  stats = alice.stats();
  EXPECT_EQ(stats.sessions, 1u);
  EXPECT_EQ(stats.objects, 2u);
  EXPECT_EQ(stats.fields, 1u);
  // Alice's items are all still there, still hers (Bob's wall may still be listed while it fades).
  Owned still;
  for (const auto& entry : owners(alice)) {
    if (entry.first != own_id) still.push_back(entry);
  }
  EXPECT_EQ(still, alices);
  // The floor still carries Alice's push, 5 N at 5 mm, and the puck has not moved.
  alice.set_operator(OperatorInput::push({0, 0, -5.0}));
  EXPECT_NEAR(step_and_get(alice, 3000).position.z, -0.005, 1e-6);
  EXPECT_EQ(alice.object_states().at(0).position, puck_at);
  // Its owner still can change and remove them.
  EXPECT_NO_THROW(puck.update(SphereSpec{.center = puck_at + Vec3{0.01, 0, 0}, .radius = 0.01,
                                         .impedance = {1000.0, 2.0},
                                         .dynamics = {.mass = 0.1, .damping = 4.0}, .shared = true}));
  EXPECT_NO_THROW(damper.remove());
  EXPECT_EQ(alice.stats().fields, 0u);
}

}  // namespace
}  // namespace haptic
