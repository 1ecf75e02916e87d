// The documents' devices (003 five-bar, 004 joystick, 001 disturbance-observer axis) running in
// hapticd from their configuration, in lockstep, driven through the SDK.
#include <gtest/gtest.h>

#include <haptic/haptic.hpp>

#include <cmath>

#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"

namespace haptic {
namespace {

using test::config_for;
using test::step_and_get;

bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

TEST(FiveBarDevice, RunsFromItsConfigurationAndRestsOnAWallWithTheEstimator_Fig6_19) {
  test::ServerProcess server(test::lockstep_config(R"("simulated_five_bar": {"velocity": "estimator"})"));
  Client client(config_for(server));
  const DeviceInfo& info = client.device_info();
  EXPECT_EQ(info.model, "five_bar_003");
  EXPECT_EQ(info.dof, 3u);
  EXPECT_TRUE(info.capabilities.friction);
  EXPECT_TRUE(info.capabilities.quantized_position);
  EXPECT_TRUE(info.capabilities.state_estimator);
  EXPECT_FALSE(info.capabilities.gravity);  // balanced (L2371–2380)
  // At rest at home the tip is at (0.6, 0, 0.3) m (eq. 3.118 with l1 = 0.3, l_f = 0.6).
  State s = step_and_get(client, 500);
  EXPECT_NEAR(s.position.x, 0.6, 1e-9);
  EXPECT_NEAR(s.position.z, 0.3, 1e-9);
  EXPECT_EQ(s.flags & kDeviceFault, 0u);
  // A stiff wall 2 mm behind the tip (normal +x; the axial joint moves the tip along x), and a
  // hand pushing 3 N into it.
  auto wall = client.add_wall({.point = {0.598, 0, 0}, .normal = {1, 0, 0}, .impedance = {2000.0, 5.0}});
  client.set_operator(OperatorInput::push({-3.0, 0, 0}));
  s = step_and_get(client, 3000);
  EXPECT_TRUE(finite(s.position) && finite(s.force));
  EXPECT_EQ(s.contact_count, 1u);
  // Friction (0.088 N·m at the 0.30 m arm: 0.29 N) lets the wall carry 3 N ± 0.3 N.
  EXPECT_NEAR(s.force.x, 3.0, 0.35);
  EXPECT_LT(s.position.x, 0.598);
  EXPECT_GT(s.position.x, 0.598 - 0.003);
}

TEST(JoystickDevice, WatchdogTripIsADeviceFaultEveryClientSeesAndItReArms_L1930) {
  test::ServerProcess server(
      test::lockstep_config(R"("simulated_joystick": {"rearm_after_s": 0.2})"));
  Client client(config_for(server));
  const DeviceInfo& info = client.device_info();
  EXPECT_EQ(info.model, "joystick_004");
  EXPECT_TRUE(info.capabilities.brakes);
  EXPECT_FALSE(info.capabilities.gravity);
  State s = step_and_get(client, 200);
  EXPECT_EQ(s.flags & kDeviceFault, 0u);
  // The hand throws the handle sideways: θ̇ passes 8 rad/s, the watchdog trips, the brakes stop it.
  // Stepped one tick at a time, so every faulted tick is seen and counted here.
  client.set_operator(OperatorInput::push({25.0, 0, 0}));
  std::uint64_t faulted_ticks = 0;
  for (int i = 0; i < 400 && faulted_ticks == 0; ++i) {
    s = step_and_get(client, 1);
    if ((s.flags & kDeviceFault) != 0) ++faulted_ticks;
  }
  ASSERT_EQ(faulted_ticks, 1u);
  EXPECT_EQ(s.force.x, 0.0);
  EXPECT_TRUE(finite(s.position));
  // Let go: still for 0.2 s, the device re-arms and the fault flag clears.
  client.set_operator(OperatorInput::release());
  for (int i = 0; i < 1000 && (s.flags & kDeviceFault) != 0; ++i) {
    s = step_and_get(client, 1);
    if ((s.flags & kDeviceFault) != 0) ++faulted_ticks;
  }
  EXPECT_EQ(s.flags & kDeviceFault, 0u);
  EXPECT_GE(faulted_ticks, 200u);  // at least the 0.2 s of rest (rearm_after_s) at 1 kHz
  // The server counted exactly the ticks every client saw flagged.
  EXPECT_EQ(client.stats().device_faults, faulted_ticks);
}

TEST(ParallelDobDevice, WallWithTheOptimalDampingHoldsTheFiveNewtonPush_Fig9) {
  test::ServerProcess server(test::lockstep_config(R"("simulated_parallel_dob": {})"));
  Client client(config_for(server));
  const DeviceInfo& info = client.device_info();
  EXPECT_EQ(info.model, "parallel_2dof_001");
  EXPECT_TRUE(info.capabilities.disturbance_observer);
  State s = step_and_get(client, 100);
  const double start_y = s.position.y;
  // The document's experiment: K = 1000 N/m, B_c at the transparency optimum (15.46 N·s/m,
  // wall_design), operator force −5 N: at rest 5 mm inside.
  const double wall_y = start_y - 0.005;
  auto wall = client.add_wall({.point = {0, wall_y, 0}, .normal = {0, 1, 0}, .impedance = {1000.0, 15.46}});
  client.set_operator(OperatorInput::push({0, -5.0, 0}));
  s = step_and_get(client, 1000);
  EXPECT_EQ(s.flags & kDeviceFault, 0u);
  EXPECT_NEAR(s.position.y, wall_y - 0.005, 1e-4);
  EXPECT_NEAR(s.force.y, 5.0, 0.1);
}

}  // namespace
}  // namespace haptic
