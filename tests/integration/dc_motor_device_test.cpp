// Document 000's 1-DOF device running in hapticd (lockstep), driven through the SDK.
#include <gtest/gtest.h>

#include <haptic/haptic.hpp>

#include <cmath>

#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"

namespace haptic {
namespace {

using test::config_for;
using test::step_and_get;

constexpr double kLength = 0.2;  // default link length, m
constexpr double kAngle = 0.5;   // initial load angle, rad

class DcMotorDevice : public ::testing::Test {
 protected:
  test::ServerProcess server_{test::lockstep_config(R"("simulated_dc_motor": {"initial_angle": 0.5})")};
};

TEST_F(DcMotorDevice, ReportsItselfAndHoldsUnderGravityCompensation_Eq6_7) {
  Client client(config_for(server_));
  EXPECT_EQ(client.device_info().dof, 1u);
  EXPECT_NE(client.device_info().name.find("000"), std::string::npos);
  EXPECT_EQ(client.device_info().model, "dc_motor_000");
  EXPECT_TRUE(client.device_info().capabilities.gravity);
  EXPECT_FALSE(client.device_info().capabilities.brakes);
  // Released at rest, gravity compensation (eq. 6.7) holds the link where it is.
  const State s = step_and_get(client, 2000);
  EXPECT_NEAR(s.position.x, kLength * std::cos(kAngle), 1e-9);
  EXPECT_NEAR(s.position.y, kLength * std::sin(kAngle), 1e-9);
  EXPECT_EQ(s.position.z, 0.0);
}

TEST_F(DcMotorDevice, LinkPressedOntoAWallFeelsItThroughTheJacobian_Eq4_3) {
  Client client(config_for(server_));
  // A floor 20 mm below the tool's start (at y = 0.0959 m); the hand pushes 1 N straight down.
  const double floor_y = kLength * std::sin(kAngle) - 0.02;
  auto floor = client.add_wall({.point = {0, floor_y, 0}, .normal = {0, 1, 0}, .impedance = {1000.0, 1.0}});
  client.set_operator(OperatorInput::push({0, -1.0, 0}));
  const State s = step_and_get(client, 5000);
  // At rest the torques balance, Jᵀ(F_wall + F_hand) = 0; both forces are vertical, so the wall
  // pushes 1 N up: 1 mm of penetration.
  EXPECT_EQ(s.contact_count, 1u);
  EXPECT_NEAR(s.force.y, 1.0, 1e-3);
  EXPECT_NEAR(s.position.y, floor_y - 0.001, 1e-6);
  // The tool stays on its circle.
  EXPECT_NEAR(std::hypot(s.position.x, s.position.y), kLength, 1e-12);
}

}  // namespace
}  // namespace haptic
