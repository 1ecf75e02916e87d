// Several device ports sharing one scene, against the real hapticd in lockstep: two users, each
// on their own simulated point mass, push one virtual mass together at the speed 000 eq. 7.1
// predicts; every session's device info and state belong to its port; a port the server lacks is
// refused naming the field.
#include <gtest/gtest.h>

#include <haptic/haptic.hpp>

#include <chrono>
#include <string>

#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"

namespace haptic {
namespace {

using test::config_for;
using test::step_and_get;

using std::chrono::seconds;

// Port 0: the default point mass at (0, 0, 20 mm); port 1: a point mass 20 mm to its side, with
// its own damping and force limit so that its DeviceInfo and state are told apart.
constexpr double kDamping0 = 0.022;  // Unit: N·s/m (the default).
constexpr double kDamping1 = 0.05;   // Unit: N·s/m.
const std::string kExtraDevice = R"("extra_devices": [{"simulated_point_mass": {
    "damping": 0.05, "max_force": 15, "initial_position": {"y": 0.02, "z": 0.02}}}])";

TEST(MultiUser, TwoUsersPushOneVirtualMassAtTheSpeedEq7_1PredictsForBothForces) {
  test::ServerProcess server(test::lockstep_config(kExtraDevice));
  Client user0(config_for(server, "user-0", 0));
  Client user1(config_for(server, "user-1", 1));
  Client watcher(config_for(server, "watcher", 0));

  // Each session is told about its own port's device.
  EXPECT_EQ(user0.device_info().max_force, 20.0);
  EXPECT_EQ(user1.device_info().max_force, 15.0);
  EXPECT_EQ(watcher.device_info().max_force, 20.0);

  // A 100 g box on a viscous floor (B_V = 4 N·s/m), its -x face at x = 15 mm, in front of both.
  constexpr double kBoxDamping = 4.0;
  auto box = user0.add_box({.pose = {.position = {0.02, 0.01, 0.02}},
                            .half_extents = {0.005, 0.03, 0.01},
                            .impedance = {.stiffness = 1000.0, .damping = 2.0},
                            .dynamics = {.mass = 0.1, .damping = kBoxDamping}});
  user0.step(10);
  constexpr double kForce0 = 0.2;  // Unit: N.
  constexpr double kForce1 = 0.3;  // Unit: N.
  user0.set_operator(OperatorInput::push({kForce0, 0, 0}));
  user1.set_operator(OperatorInput::push({kForce1, 0, 0}));
  const std::uint64_t tick = user0.step(700);

  // Tools and box move together: F_0 + F_1 = (B_V + b_0 + b_1) v (eq. 7.1 plus each device's
  // m ẍ + b ẋ = F, in steady state).
  const double v_expected = (kForce0 + kForce1) / (kBoxDamping + kDamping0 + kDamping1);
  const std::vector<ObjectState> seen = watcher.object_states();
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].id, box.id());
  EXPECT_NEAR(seen[0].velocity.x, v_expected, 1e-4);
  EXPECT_NEAR(seen[0].position.y, 0.01, 1e-12);
  // With one user alone it would be far slower: both forces reached the box.
  EXPECT_GT(seen[0].velocity.x, kForce1 / (kBoxDamping + kDamping1) * 1.5);

  // Each session's state is its own port's tool: both moved with the box, each at its own y,
  // each pressing with its own hand's force.
  State state0, state1;
  ASSERT_TRUE(user0.wait_for_tick(tick, state0, seconds(5)));
  user1.subscribe(1);
  const std::uint64_t next = user1.step(1);
  ASSERT_TRUE(user1.wait_for_tick(next, state1, seconds(5)));
  EXPECT_NEAR(state0.position.y, 0.0, 1e-9);
  EXPECT_NEAR(state1.position.y, 0.02, 1e-9);
  EXPECT_NEAR(state0.velocity.x, v_expected, 1e-4);
  EXPECT_NEAR(state1.velocity.x, v_expected, 1e-4);
  // The box pushes back on each tool with that hand's force less the tool's own damping.
  EXPECT_NEAR(-state0.force.x, kForce0 - kDamping0 * v_expected, 2e-3);
  EXPECT_NEAR(-state1.force.x, kForce1 - kDamping1 * v_expected, 2e-3);

  // The watcher's own stream is port 0's tool.
  watcher.subscribe(1);
  const std::uint64_t watched = watcher.step(1);
  State seen_by_watcher;
  ASSERT_TRUE(watcher.wait_for_tick(watched, seen_by_watcher, seconds(5)));
  EXPECT_NEAR(seen_by_watcher.position.y, 0.0, 1e-9);
}

TEST(MultiUser, ADeviceIndexTheServerLacksIsRefusedNamingTheField) {
  test::ServerProcess server(test::lockstep_config(kExtraDevice));
  try {
    Client client(config_for(server, "nowhere", 2));
    FAIL() << "device_index 2 was accepted by a server with two ports";
  } catch (const InvalidArgumentError& error) {
    EXPECT_NE(std::string(error.what()).find("device_index"), std::string::npos) << error.what();
  }
  // A one-device server has port 0 only.
  test::ServerProcess single(test::lockstep_config());
  EXPECT_THROW(Client(config_for(single, "nowhere", 1)), InvalidArgumentError);
  EXPECT_NO_THROW(Client(config_for(single, "here", 0)));
}

}  // namespace
}  // namespace haptic
