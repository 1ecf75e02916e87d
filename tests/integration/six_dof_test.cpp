// The 6-DOF point mass through the whole server and the SDK, in lockstep: the device says it takes
// torques, an orientation spring comes back with its stability report on the handle, its torque
// arrives in the state, and one past the margin is accepted with a warning.
#include <gtest/gtest.h>

#include <haptic/haptic.hpp>

#include <cmath>
#include <string>

#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"

namespace haptic {
namespace {

using test::config_for;
using test::step_and_get;

/// Lockstep, the handle 0.2 rad about z from identity (I 1e-4 kg·m², b 5e-4 N·m·s/rad).
std::string six_dof_config() {
  return R"({"time_mode": "LOCKSTEP", "udp_address": "127.0.0.1", "status_period_s": 0,
             "real_time": {"use_fifo": false},
             "simulated_point_mass": {"rotation": {"initial_orientation":
                 {"w": 0.9950041652780258, "z": 0.09983341664682815}}}})";
}

TEST(SixDof, AnOrientationSpringReportsItsStabilityAndItsTorqueArrivesInTheState) {
  test::ServerProcess server(six_dof_config());
  Client client(config_for(server));
  const DeviceInfo& info = client.device_info();
  EXPECT_EQ(info.dof, 6u);
  EXPECT_TRUE(info.capabilities.orientation);
  EXPECT_TRUE(info.capabilities.torque);
  EXPECT_EQ(info.max_torque, 0.2);

  OrientationSpringSpec spring;
  spring.stiffness = 0.05;
  spring.damping = 2e-4;
  FieldHandle handle = client.add_field(spring);
  ASSERT_TRUE(handle.stability().has_value());
  const StabilityReport& report = *handle.stability();
  EXPECT_TRUE(report.device_known);
  EXPECT_EQ(report.device_mass, 1e-4);      // the handle's inertia, kg·m²
  EXPECT_EQ(report.device_damping, 5e-4);   // N·m·s/rad
  EXPECT_TRUE(report.stable);
  EXPECT_GT(report.max_stable_stiffness, 1.0);  // 1.40 N·m/rad with this damper at 1 kHz
  EXPECT_TRUE(report.warning.empty());

  const State s = step_and_get(client, 5);
  ASSERT_TRUE(s.torque.has_value());
  // τ = −k θ − b ω; the spring fades in over the removal ramp (50 ticks), so a few ticks after it
  // arrived it is a fraction of that, along −z.
  EXPECT_LT(s.torque->z, 0.0);
  EXPECT_GT(s.torque->z, -0.05 * 0.2 - 1e-12);
  const State later = step_and_get(client, 200);
  ASSERT_TRUE(later.torque.has_value() && later.orientation.has_value());
  const double angle = 2.0 * std::atan2(later.orientation->z, later.orientation->w);
  EXPECT_LT(std::abs(angle), 0.2);  // turned towards the target

  OrientationSpringSpec stiff = spring;
  stiff.stiffness = 3.0 * report.max_stable_stiffness;
  FieldHandle too_stiff = client.add_field(stiff);
  ASSERT_TRUE(too_stiff.stability().has_value());
  EXPECT_FALSE(too_stiff.stability()->stable);
  EXPECT_NE(too_stiff.stability()->warning.find("N*m/rad"), std::string::npos) << too_stiff.stability()->warning;

  // Other fields carry no report.
  EXPECT_FALSE(client.add_field(ViscousFieldSpec{.damping = 0.1}).stability().has_value());
}

TEST(SixDof, APointMassWithoutAHandleTakesNoTorque) {
  test::ServerProcess server(R"({"time_mode": "LOCKSTEP", "udp_address": "127.0.0.1", "status_period_s": 0,
                                 "real_time": {"use_fifo": false}})");
  Client client(config_for(server));
  EXPECT_FALSE(client.device_info().capabilities.torque);
  EXPECT_EQ(client.device_info().max_torque, 0.0);
  OrientationSpringSpec spring;
  spring.stiffness = 0.05;
  FieldHandle handle = client.add_field(spring);
  ASSERT_TRUE(handle.stability().has_value());
  EXPECT_FALSE(handle.stability()->device_known);  // no handle to model
  const State s = step_and_get(client, 10);
  EXPECT_FALSE(s.torque.has_value());
}

}  // namespace
}  // namespace haptic
