// The real hapticd driven by the real SDK, in lockstep time: walls push back with K × penetration,
// removed objects ramp out, clients only touch their own objects, and a silent client loses its
// objects.
#include <gtest/gtest.h>

#include <haptic/haptic.hpp>

#include <chrono>
#include <cmath>
#include <string>
#include <thread>

#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"

namespace haptic {
namespace {

using test::config_for;
using test::step_and_get;

using std::chrono::seconds;

constexpr double kK = 1000.0;  // wall stiffness, N/m
constexpr double kB = 1.0;     // wall damping, N·s/m
constexpr std::int64_t kRampTicks = 50;  // default removal ramp: 50 ms at 1 kHz

double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

class SdkIntegration : public ::testing::Test {
 protected:
  // The default lease (1 s): a test whose point is not a lost client must not lose one because
  // a loaded machine held it up for a few hundred milliseconds.
  test::ServerProcess server_{test::lockstep_config()};
};

TEST_F(SdkIntegration, WallPushesBackWithStiffnessTimesPenetrationAlongItsNormal) {
  Client client(config_for(server_, "wall"));
  EXPECT_TRUE(client.device_info().simulated);
  EXPECT_EQ(client.device_info().model, "point_mass");
  EXPECT_FALSE(client.device_info().capabilities.gravity);
  EXPECT_EQ(client.device_info().loop_rate_hz, 1000.0);
  // A tilted wall through the origin; the hand pushes 5 N straight into it (Eom et al.'s −5 N).
  const Vec3 n{0.0, 0.6, 0.8};
  auto wall = client.add_wall({.point = {0, 0, 0}, .normal = n, .impedance = {kK, kB}});
  client.set_operator(OperatorInput::push({0.0, -5.0 * n.y, -5.0 * n.z}));
  const State s = step_and_get(client, 3000);

  const double penetration = -dot(s.position, n);
  EXPECT_GT(penetration, 0.0);
  EXPECT_EQ(s.contact_count, 1u);
  // At each sample the force is exactly K × penetration − B × normal velocity, along n.
  const double expected = kK * penetration - kB * dot(s.velocity, n);
  EXPECT_NEAR(s.force.x, 0.0, 1e-12);
  EXPECT_NEAR(s.force.y, expected * n.y, 1e-9);
  EXPECT_NEAR(s.force.z, expected * n.z, 1e-9);
  // At rest it balances the push: 5 N at 5 mm.
  EXPECT_NEAR(penetration, 0.005, 1e-6);
  EXPECT_NEAR(std::sqrt(dot(s.force, s.force)), 5.0, 1e-3);
  // The proxy sits on the surface.
  EXPECT_NEAR(dot(s.proxy, n), 0.0, 1e-12);

  // Delete it: the force ramps out over 50 ticks and is exactly zero after.
  wall.remove();
  const State mid = step_and_get(client, kRampTicks / 2);
  EXPECT_GT(mid.force.z, 0.0);
  EXPECT_LT(mid.force.z, s.force.z);
  EXPECT_TRUE(mid.flags & kRampingOut);
  const State after = step_and_get(client, kRampTicks);
  EXPECT_EQ(after.force.x, 0.0);
  EXPECT_EQ(after.force.y, 0.0);
  EXPECT_EQ(after.force.z, 0.0);
  EXPECT_EQ(after.contact_count, 0u);
}

TEST_F(SdkIntegration, TwoClientsEachSeeAndChangeOnlyTheirOwnObjects) {
  Client alice(config_for(server_, "alice"));
  Client bob(config_for(server_, "bob"));
  EXPECT_NE(alice.session_id(), bob.session_id());

  auto floor = alice.add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1}, .impedance = {kK, kB}});
  auto ball = bob.add_sphere({.center = {0.05, 0, 0}, .radius = 0.01, .impedance = {kK, 0.0}});
  EXPECT_NE(floor.id(), ball.id());
  EXPECT_EQ(alice.stats().objects, 2u);  // one shared scene

  alice.set_operator(OperatorInput::push({0, 0, -5.0}));
  const State pressed = step_and_get(alice, 3000);
  EXPECT_NEAR(pressed.force.z, 5.0, 1e-3);

  // Bob changes and removes his own sphere: Alice's wall is untouched.
  ball.update(SphereSpec{.center = {0.06, 0, 0}, .radius = 0.02, .impedance = {kK, 0.0}});
  ball.remove();
  const State still = step_and_get(bob, 200);
  EXPECT_NEAR(still.force.z, 5.0, 1e-3);
  // Both streams carry the same shared device state.
  State seen_by_alice;
  ASSERT_TRUE(alice.wait_for_tick(still.tick, seen_by_alice, seconds(5)));
  EXPECT_EQ(seen_by_alice.force.z, still.force.z);

  // Alice moves her wall up 1 mm: the equilibrium follows (5 mm below the new surface).
  floor.update(WallSpec{.point = {0, 0, 0.001}, .normal = {0, 0, 1}, .impedance = {kK, kB}});
  const State moved = step_and_get(alice, 3000);
  EXPECT_NEAR(moved.position.z, 0.001 - 0.005, 1e-6);
}

TEST(SdkIntegrationShortLease, ASilentClientLosesItsObjectsAndTheirForceRampsOut) {
  // A short lease, here only: the lost client is the point.
  test::ServerProcess server_{test::lockstep_config(R"("lease_timeout_ms": 300)")};
  Client watcher(config_for(server_, "watcher"));
  auto lost = std::make_unique<Client>(config_for(server_, "lost"));
  auto wall = lost->add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1}, .impedance = {kK, kB}});
  watcher.set_operator(OperatorInput::push({0, 0, -5.0}));
  const State pressed = step_and_get(watcher, 3000);
  ASSERT_NEAR(pressed.force.z, 5.0, 1e-3);

  lost->set_heartbeats_enabled(false);  // and it makes no more calls: its lease (300 ms) runs out
  const auto give_up = std::chrono::steady_clock::now() + seconds(10);
  while (watcher.stats().leases_expired == 0 && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(watcher.stats().leases_expired, 1u);
  EXPECT_EQ(watcher.stats().sessions, 1u);

  // The loop stood still while we waited (lockstep): the fade starts at the next tick and each
  // sample's force is exactly the faded wall law.
  for (std::int64_t k = 0; k <= kRampTicks + 5; ++k) {
    const State s = step_and_get(watcher, 1);
    const double gain = std::max(0.0, 1.0 - static_cast<double>(k) / kRampTicks);
    const double unfaded = std::max(0.0, -kK * s.position.z - kB * s.velocity.z);
    ASSERT_NEAR(s.force.z, gain * unfaded, 1e-9) << "k = " << k;
  }
  EXPECT_EQ(step_and_get(watcher, 1).force.z, 0.0);

  // The lost client finds out on its next call.
  EXPECT_THROW(lost->add_wall({.normal = {0, 0, 1}, .impedance = {kK, kB}}), NotFoundError);
  wall.release();
  lost.reset();  // closing a session that is gone does not throw
}

TEST_F(SdkIntegration, LockstepRunsAreExactlyReproducible) {
  auto run = [this] {
    Client client(config_for(server_, "repro"));
    auto wall = client.add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1}, .impedance = {kK, kB}});
    client.set_operator(OperatorInput::follow({0.001, 0.0, -0.01}, 200.0, 2.0));
    const State s = step_and_get(client, 1500);
    wall.remove();
    client.set_operator(OperatorInput::release());
    step_and_get(client, 500);
    return s;
  };
  // Two runs on one server start from different device states, so compare against a fresh server.
  const State first = run();
  test::ServerProcess other(test::lockstep_config());
  ClientConfig config = config_for(other, "repro");
  Client client(config);
  auto wall = client.add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1}, .impedance = {kK, kB}});
  client.set_operator(OperatorInput::follow({0.001, 0.0, -0.01}, 200.0, 2.0));
  const State second = step_and_get(client, 1500);
  EXPECT_EQ(first.position, second.position);
  EXPECT_EQ(first.force, second.force);
  EXPECT_EQ(first.server_time, second.server_time);
}

TEST_F(SdkIntegration, OperatorProfilesAndGripsRunOnTheServersClock) {
  Client client(config_for(server_, "profiles"));
  auto wall = client.add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1}, .impedance = {kK, kB}});
  // Settle on the wall with a light push, then ramp the push from 0 to 5 N over 1 s.
  client.set_operator(OperatorInput::push({0, 0, -0.1}));
  step_and_get(client, 2000);
  OperatorInput::Profile ramp;
  ramp.shape = OperatorInput::Profile::Shape::kRamp;
  ramp.rise_s = 1.0;
  client.set_operator(OperatorInput::push({0, 0, -5.0}, ramp));
  // The tool is light (10 g) and the ramp slow: the wall's force follows the push quasi-statically.
  EXPECT_NEAR(step_and_get(client, 500).force.z, 2.5, 0.05);
  EXPECT_NEAR(step_and_get(client, 1500).force.z, 5.0, 1e-3);

  // A tight grip takes the tool off the wall along a line to 10 mm above it.
  client.set_operator(OperatorInput::follow_line({0, 0, -0.005}, {0, 0, 0.01}, 0.5,
                                                 OperatorInput::Grip::kTight));
  const State lifted = step_and_get(client, 3000);
  EXPECT_NEAR(lifted.position.z, 0.01, 1e-4);
  EXPECT_EQ(lifted.contact_count, 0u);
  EXPECT_THROW(client.set_operator(OperatorInput::follow_line({}, {}, -1.0, OperatorInput::Grip::kLoose)),
               InvalidArgumentError);
}

TEST_F(SdkIntegration, ErrorsAreTypedAndCarryTheServersMessage) {
  Client client(config_for(server_, "errors"));
  try {
    client.add_sphere({.center = {0, 0, 100.0}, .radius = 0.01, .impedance = {kK, 0.0}});
    FAIL() << "expected InvalidArgumentError";
  } catch (const InvalidArgumentError& error) {
    EXPECT_NE(std::string(error.what()).find("object.pose.position.z"), std::string::npos)
        << error.what();
  }
  EXPECT_THROW(client.add_wall({.normal = {0, 0, 0}, .impedance = {kK, kB}}), InvalidArgumentError);
  EXPECT_THROW(client.subscribe(5000), InvalidArgumentError);
  EXPECT_THROW(client.step(0), InvalidArgumentError);
  EXPECT_EQ(client.stats().objects, 0u);
}

// An item marked across_sites is for the other sites of a federation; this server is in none, so
// it refuses the item and the SDK's error carries its message: nothing is created, alone or in a
// whole scene.
TEST_F(SdkIntegration, AnAcrossSitesSphereIsRefusedOutsideAFederationAndNothingIsCreated) {
  Client client(config_for(server_, "across_sites"));
  const SphereSpec sphere{.center = {0.05, 0, 0}, .radius = 0.01, .impedance = {kK, 0.0},
                          .across_sites = true};
  const std::string not_federated =
      ".across_sites: this server is not in a federation (its configuration has no federation section)";
  try {
    (void)client.add_sphere(sphere);
    ADD_FAILURE() << "an across_sites sphere was created outside a federation";
  } catch (const FailedPreconditionError& error) {
    EXPECT_EQ(std::string(error.what()), "CreateObject: object" + not_federated);
    EXPECT_EQ(error.code(), ErrorCode::kFailedPrecondition);
  }
  try {
    (void)client.apply_scene(SceneSpec{.objects = {sphere}, .fields = {}});
    ADD_FAILURE() << "a scene with an across_sites sphere was applied outside a federation";
  } catch (const FailedPreconditionError& error) {
    EXPECT_EQ(std::string(error.what()), "ApplyScene: scene.objects[0]" + not_federated);
  }
  EXPECT_TRUE(client.scene(true).object_ids.empty());
  EXPECT_EQ(client.stats().objects, 0u);
}

TEST(SdkIntegrationRealTime, StepIsRefusedOutsideLockstepAndStateStreams) {
  test::ServerProcess server(R"({"time_mode": "REAL_TIME", "udp_address": "127.0.0.1",
      "status_period_s": 0, "real_time": {"use_fifo": false}})");
  Client client(config_for(server, "realtime"));
  try {
    (void)client.step(1);
    ADD_FAILURE() << "a real-time server stepped";
  } catch (const FailedPreconditionError& error) {
    EXPECT_EQ(std::string(error.what()), "Step: the server runs in REAL_TIME; start it with time_mode LOCKSTEP");
  }
  State state;
  ASSERT_TRUE(client.poll_state(state, seconds(5)));
  State next;
  ASSERT_TRUE(client.poll_state(next, seconds(5)));
  EXPECT_GT(next.sequence, state.sequence);
  // Server time counts from the loop's start, on this host's CLOCK_MONOTONIC (which is this
  // process's steady clock): so server − local lies between −(when it was ready) and −(when it
  // was started), and the estimate is at most the true offset and at least what the newest
  // sample shows (server time − receipt).
  ASSERT_TRUE(client.clock_offset().has_value());
  const auto offset = *client.clock_offset();
  const auto since_epoch = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch());
  };
  EXPECT_LE(offset, -since_epoch(server.forked_at()));
  EXPECT_GE(offset, -since_epoch(server.ready_at()) - std::chrono::milliseconds(50));
  EXPECT_GE(offset, std::chrono::nanoseconds(std::llround(next.server_time * 1e9)) -
                        since_epoch(next.received_at));
  EXPECT_EQ(client.receive_counters().rejected, 0u);
}

// GetStats shows each client's stream from both ends: what the server sent it, what its heartbeats
// say arrived, and the round trip their echoes measure; the loop's figures cover a sliding window.
TEST(SdkIntegrationRealTime, StatsShowEachClientsStreamFromBothEnds) {
  test::ServerProcess server(R"({"time_mode": "REAL_TIME", "udp_address": "127.0.0.1",
      "status_period_s": 0, "real_time": {"use_fifo": false}})");
  Client every_tick(config_for(server, "every-tick"));
  ClientConfig tenth = config_for(server, "every-tenth");
  tenth.state_decimation = 10;
  Client every_tenth(tenth);
  ClientConfig quiet = config_for(server, "no-stream");
  quiet.state_decimation = 0;
  Client no_stream(quiet);

  // A second or so of streaming, then the figures: the clients' heartbeats (every 20 ms) have
  // reported. On a loaded machine the first second may not hold enough of them: polled until it
  // does (at most 10 s), and the figures are checked on that one snapshot.
  const auto reported_enough = [&](const Stats& s) {
    if (s.clients.size() != 3u || s.lateness_samples <= 500u) return false;
    for (const ClientStats& c : s.clients) {
      if (c.heartbeats < 20u) return false;
      if (c.decimation > 0 && (c.round_trip_samples < 10u || c.states_received == 0u)) return false;
    }
    return true;
  };
  std::this_thread::sleep_for(std::chrono::milliseconds(1200));
  Stats stats = no_stream.stats();
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!reported_enough(stats) && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    stats = no_stream.stats();
  }
  ASSERT_EQ(stats.clients.size(), 3u);
  const auto find = [&](std::uint64_t id) -> const ClientStats& {
    for (const ClientStats& c : stats.clients) {
      if (c.session_id == id) return c;
    }
    ADD_FAILURE() << "no client " << id;
    return stats.clients.front();
  };
  const ClientStats& fast = find(every_tick.session_id());
  const ClientStats& slow = find(every_tenth.session_id());
  const ClientStats& none = find(no_stream.session_id());
  EXPECT_EQ(fast.client_name, "every-tick");
  EXPECT_EQ(fast.peer, "127.0.0.1");
  EXPECT_EQ(fast.decimation, 1u);
  EXPECT_EQ(slow.decimation, 10u);
  EXPECT_EQ(none.decimation, 0u);
  EXPECT_EQ(none.datagrams_sent, 0u);
  EXPECT_EQ(none.states_received, 0u);
  EXPECT_EQ(none.round_trip_samples, 0u);  // nothing to echo
  // Each stream sent something, and never more than its decimation allows over the ticks run
  // (a loaded sender conflates, so only the upper bounds are exact).
  EXPECT_GT(fast.datagrams_sent, 0u);
  EXPECT_GT(slow.datagrams_sent, 0u);
  EXPECT_LE(fast.datagrams_sent, stats.ticks);
  EXPECT_LE(slow.datagrams_sent, stats.ticks / 10 + 1);
  for (const ClientStats* c : {&fast, &slow, &none}) {
    SCOPED_TRACE(c->client_name);
    EXPECT_GE(c->heartbeats, 20u);  // 50 a second for over a second
    EXPECT_GE(c->last_heartbeat_age_s, 0.0);
    EXPECT_LT(c->last_heartbeat_age_s, 5.0);  // every 20 ms, idle; a loaded machine may stall it
    // What a heartbeat reported cannot exceed what had been numbered for it by then: sent, or
    // skipped by a sender that fell behind (a gap the client counts as lost).
    EXPECT_LE(c->states_received + c->states_lost, c->datagrams_sent + c->samples_unsent);
  }
  for (const ClientStats* c : {&fast, &slow}) {
    SCOPED_TRACE(c->client_name);
    EXPECT_GT(c->states_received, 0u);
    EXPECT_GE(c->round_trip_samples, 10u);
    EXPECT_GT(c->round_trip_p50_us, 0.0);
    EXPECT_LE(c->round_trip_p50_us, c->round_trip_p99_us);
    EXPECT_LE(c->round_trip_p99_us, c->round_trip_p999_us);
    EXPECT_LT(c->round_trip_p999_us, 1e6);  // under a second on loopback, however loaded
  }
  // The client's own counters agree with what it reported (they can only have grown since).
  EXPECT_GE(every_tick.receive_counters().accepted, fast.states_received);
  EXPECT_GE(every_tick.receive_counters().lost, fast.states_lost);

  // The loop's lateness covers the window, not the run: at most window_s + 1 seconds of ticks.
  EXPECT_EQ(stats.window_s, 10.0);
  EXPECT_GT(stats.lateness_samples, 500u);
  EXPECT_LE(stats.lateness_samples, stats.ticks);
  EXPECT_LE(stats.lateness_p50_us, stats.lateness_p99_us);
  EXPECT_LE(stats.lateness_p99_us, stats.lateness_p999_us);
  EXPECT_LE(stats.lateness_p999_us, stats.lateness_max_us);
}

}  // namespace
}  // namespace haptic
