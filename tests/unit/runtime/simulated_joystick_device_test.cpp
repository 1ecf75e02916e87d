// Document 004's joystick (Russo 1990) as a hapticd device: the description, the reading through
// eq. 3.3, commands through τ = Jᵀ F (eq. 3.18) and the hybrid rule (L1011), the watchdog (L1930)
// and the safe state.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "engine/device/gimbal_joystick.hpp"
#include "runtime/joystick_model.hpp"
#include "runtime/simulated_joystick_device.hpp"
#include "support/modelled_device.hpp"

namespace haptic::runtime {
namespace {

constexpr double kT = 1e-3;  // s, a 1 kHz loop
namespace js = engine::joystick_state;
using Joystick = Modelled<SimulatedJoystickDevice, JoystickModel>;

engine::HandInput push(const engine::Vec3& force) {
  engine::HandInput hand;
  hand.mode = engine::HandInput::Mode::kApplyForce;
  hand.force = force;
  return hand;
}

TEST(SimulatedJoystickDevice, DescribesItselfAsJoystick004) {
  const SimulatedJoystickConfig config;
  ASSERT_EQ(config.validate(), "");
  Joystick device(JoystickModel(config.model()), config);
  const DeviceDescription& d = device->description();
  EXPECT_EQ(d.model, "joystick_004");
  EXPECT_EQ(d.dof, 3u);
  EXPECT_TRUE(d.simulated);
  EXPECT_TRUE(d.capabilities.brakes);
  EXPECT_TRUE(d.capabilities.friction);
  EXPECT_FALSE(d.capabilities.gravity);
  EXPECT_DOUBLE_EQ(d.max_force, config.max_force);
  // The workspace box holds every corner of the joint ranges (eq. 3.3).
  const engine::GimbalJoystickParams& p = config.params;
  for (const double theta : {-p.gimbal_limit, 0.0, p.gimbal_limit}) {
    for (const double phi : {-p.gimbal_limit, 0.0, p.gimbal_limit}) {
      for (const double R : {p.R_min, p.R_max}) {
        const engine::Vec3 x = engine::joystick_forward({theta, phi, R});
        EXPECT_GE(x.x, d.workspace_min.x - 1e-12);
        EXPECT_LE(x.x, d.workspace_max.x + 1e-12);
        EXPECT_GE(x.y, d.workspace_min.y - 1e-12);
        EXPECT_LE(x.y, d.workspace_max.y + 1e-12);
        EXPECT_GE(x.z, d.workspace_min.z - 1e-12);
        EXPECT_LE(x.z, d.workspace_max.z + 1e-12);
      }
    }
  }
}

TEST(SimulatedJoystickDevice, ConfigValidationNamesTheField) {
  SimulatedJoystickConfig config;
  config.params.M_s = -0.1;
  EXPECT_EQ(config.validate().rfind("params.M_s: ", 0), 0u) << config.validate();
  config = {};
  config.initial.R = 0.1;  // inside R_min
  EXPECT_EQ(config.validate().rfind("initial.R: ", 0), 0u);
  config = {};
  config.max_force = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(config.validate().rfind("max_force: ", 0), 0u);
}

TEST(SimulatedJoystickDevice, ReadingIsTheHandlePositionOfEq3_3) {
  SimulatedJoystickConfig config;
  config.initial = {0.3, -0.2, 0.25};
  Joystick device(JoystickModel(config.model()), config);
  ASSERT_EQ(device->start(), DeviceStatus::kOk);
  ToolReading reading;
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  const engine::Vec3 x = engine::joystick_forward(config.initial);
  EXPECT_NEAR(reading.p_WT.x, x.x, 1e-15);
  EXPECT_NEAR(reading.p_WT.y, x.y, 1e-15);
  EXPECT_NEAR(reading.p_WT.z, x.z, 1e-15);
  EXPECT_EQ(reading.v_WT, engine::Vec3{});
  // Moving: v_WT agrees with the difference of successive positions (J q̇, eq. 3.14).
  // Above the gimbal friction and brake residual (≈ 0.28 N·m, 1.2 N at R = 0.25 m) and the
  // sleeve friction (5.66 N), so that every axis moves.
  device->set_hand(push({6.0, -1.0, 8.0}));
  ToolReading before, after;
  for (int k = 0; k < 30; ++k) ASSERT_EQ(device.write({}, kT), DeviceStatus::kOk);
  const engine::Vec3 rates = device->plant().measured_joint_rates();
  EXPECT_TRUE(rates.x != 0.0 && rates.y != 0.0 && rates.z != 0.0);
  EXPECT_FALSE(device.model.watchdog_tripped());
  device.read(before);
  const double h = 1e-5;
  device.write({}, h);
  device.read(after);
  const engine::Vec3 v = (1.0 / h) * (after.p_WT - before.p_WT);
  std::printf("  v_WT (%.4f, %.4f, %.4f) m/s, difference (%.4f, %.4f, %.4f) m/s\n", before.v_WT.x,
              before.v_WT.y, before.v_WT.z, v.x, v.y, v.z);
  EXPECT_GT(engine::norm(before.v_WT), 0.01);
  EXPECT_LT(engine::norm(v - before.v_WT), 1e-3 * engine::norm(before.v_WT) + 1e-6);
}

// Free space, at rest: a command does work on the joystick, so the motors carry all of it,
// τ = Jᵀ F (eq. 3.18), and the brakes stay off.
TEST(SimulatedJoystickDevice, FreeSpaceForceGoesToTheMotorsAsJtF_Eq3_18) {
  SimulatedJoystickConfig config;
  config.initial = {0.2, 0.1, 0.24};
  Joystick device(JoystickModel(config.model()), config);
  const engine::Vec3 F{2.0, -1.0, 3.0};
  const engine::GimbalJoystickParams& p = config.params;
  const engine::Vec3 tau = engine::joystick_multiply_transposed(
      engine::joystick_jacobian(config.initial.theta, config.initial.phi, config.initial.R / p.r, p.r), F);
  ASSERT_EQ(device.write({F}, kT), DeviceStatus::kOk);
  const engine::JoystickActuatorCommand& c = device->last_command();
  std::printf("  tau = (%.4f, %.4f, %.4f) N.m; motors (%.4f, %.4f, %.4f); brakes (%g, %g, %g)\n",
              tau.x, tau.y, tau.z, c.motor[0], c.motor[1], c.motor[2], c.brake[0], c.brake[1],
              c.brake[2]);
  EXPECT_NEAR(c.motor[0], tau.x, 1e-12);
  EXPECT_NEAR(c.motor[1], tau.y, 1e-12);
  EXPECT_NEAR(c.motor[2], tau.z, 1e-12);
  EXPECT_EQ(c.brake[0], 0.0);
  EXPECT_EQ(c.brake[1], 0.0);
  EXPECT_EQ(c.brake[2], 0.0);
  EXPECT_NEAR(tau.z, p.r * engine::dot(F, engine::joystick_shaft_direction(0.2, 0.1)), 1e-15);
}

/// The hand swinging the handle ±30 mm along x at 1 Hz about where it starts.
engine::HandInput swinging_hand(const SimulatedJoystickConfig& config) {
  engine::HandInput hand;
  hand.mode = engine::HandInput::Mode::kFollowTarget;
  hand.target = engine::joystick_forward(config.initial);
  hand.stiffness = 800.0;
  hand.damping = 15.0;
  hand.mass = 0.2;
  hand.trajectory.shape = engine::TargetTrajectory::Shape::kSine;
  hand.trajectory.amplitude = {0.03, 0.0, 0.0};
  hand.trajectory.frequency_hz = 1.0;
  return hand;
}

// A damper scene (F = −B v) while the hand swings the handle: every axis that moves is braked
// and its motor is idle (eq. 4.7 through L1011's rule); the brakes only take power in.
TEST(SimulatedJoystickDevice, ADamperSceneIsRenderedByTheBrakes_Eq4_7) {
  SimulatedJoystickConfig config;
  Joystick device(JoystickModel(config.model()), config);
  device->set_hand(swinging_hand(config));
  const double B = 5.0;  // N·s/m
  int moving = 0, braked = 0;
  double min_brake_power = 0.0;
  for (int k = 0; k < 2000; ++k) {
    ToolReading r;
    ASSERT_EQ(device.read(r), DeviceStatus::kOk);
    const double theta_dot = device->plant().measured_joint_rates().x;
    ASSERT_EQ(device.write({-B * r.v_WT}, kT), DeviceStatus::kOk);
    const engine::JoystickActuatorCommand& c = device->last_command();
    if (std::abs(theta_dot) >= config.rule_stick_velocity) {
      ++moving;
      if (c.brake[0] > 0.0 && c.motor[0] == 0.0) ++braked;
      min_brake_power = std::min(min_brake_power, c.brake[0] * std::abs(theta_dot));
    }
  }
  std::printf("  theta moving at %d ticks, braked with the motor idle at %d\n", moving, braked);
  EXPECT_GT(moving, 1500);
  EXPECT_EQ(braked, moving);
  EXPECT_GE(min_brake_power, 0.0);
  EXPECT_FALSE(device.model.watchdog_tripped());
}

// With its brakes released (the bench's identification), the same damper scene goes to the motors
// as Jᵀ F, dissipating part and all, and no brake is applied.
TEST(SimulatedJoystickDevice, WithItsBrakesReleasedTheMotorsTakeEveryCommand) {
  SimulatedJoystickConfig config;
  config.brakes_released = true;
  Joystick device(JoystickModel(config.model()), config);
  device->set_hand(swinging_hand(config));
  const double B = 5.0;  // N·s/m
  int dissipating = 0;
  for (int k = 0; k < 2000; ++k) {
    ToolReading r;
    ASSERT_EQ(device.read(r), DeviceStatus::kOk);
    const double theta_dot = device->plant().measured_joint_rates().x;
    const engine::Vec3 F = -B * r.v_WT;
    ASSERT_EQ(device.write({F}, kT), DeviceStatus::kOk);
    const engine::JoystickActuatorCommand& c = device->last_command();
    const engine::GimbalJoystickParams& p = config.params;
    const engine::JoystickPose q = engine::joystick_inverse(r.p_WT);
    const double tau = engine::joystick_multiply_transposed(
        engine::joystick_jacobian(q.theta, q.phi, q.R / p.r, p.r), F).x;
    EXPECT_NEAR(c.motor[0], tau, 1e-3 * std::abs(tau) + 1e-9) << k;
    EXPECT_EQ(c.brake[0], 0.0);
    EXPECT_EQ(c.brake[1], 0.0);
    EXPECT_EQ(c.brake[2], 0.0);
    dissipating += c.motor[0] * theta_dot < 0.0;
  }
  EXPECT_GT(dissipating, 1500);  // the motors, not the brakes, take the power in
  EXPECT_FALSE(device.model.watchdog_tripped());
}

// L1930: the hand throws the handle; the first sample with |θ̇| past 8 rad/s trips the watchdog,
// from then on the motors are zero and the brakes at their limits, and it stays so after the
// joystick has stopped and the hand let go, until rearm().
TEST(SimulatedJoystickDevice, WatchdogTripsWithinOnePeriodAndLatches_L1930) {
  SimulatedJoystickConfig config;
  config.initial = {-0.6, 0.0, 0.24};
  Joystick device(JoystickModel(config.model()), config);
  device->set_hand(push({25.0, 0.0, 0.0}));  // 6 N·m about θ: below the braked capacity 7.98 N·m
  int tripped_at = -1;
  double rate_before = 0.0, rate_at = 0.0;
  for (int k = 0; k < 300; ++k) {
    ToolReading r;
    ASSERT_EQ(device.read(r), DeviceStatus::kOk);
    const double before = device->plant().measured_joint_rates().x;
    ASSERT_EQ(device.write({}, kT), DeviceStatus::kOk);
    const double after = device->plant().measured_joint_rates().x;
    if (tripped_at < 0 && std::abs(after) > 8.0) {
      tripped_at = k;
      rate_before = before;
      rate_at = after;
      // The very next sample trips it, before any command is computed from it: the watchdog
      // checks the tachometers every tick (the next loop pass reads the same sample).
      ToolReading next;
      ASSERT_EQ(device.read(next), DeviceStatus::kOk);
      EXPECT_TRUE(device.model.watchdog_tripped());
      EXPECT_TRUE(device.model.in_safe_state());
      EXPECT_TRUE(next.safe_state);
    }
    if (tripped_at < 0) {
      EXPECT_FALSE(device.model.watchdog_tripped()) << k;
    }
  }
  std::printf("  tripped at tick %d: theta rate %.3f rad/s (%.3f at its start)\n", tripped_at,
              rate_at, rate_before);
  ASSERT_GE(tripped_at, 0);
  EXPECT_LE(std::abs(rate_before), 8.0);
  const engine::JoystickActuatorCommand& c = device->last_command();
  const engine::GimbalJoystickParams& p = config.params;
  EXPECT_EQ(c.motor, (std::array<double, 3>{0.0, 0.0, 0.0}));
  EXPECT_EQ(c.brake, (std::array<double, 3>{p.brake_limit_gimbal, p.brake_limit_gimbal,
                                             p.brake_limit_shaft}));
  EXPECT_EQ(device->plant().measured_joint_rates().x, 0.0);  // the brakes hold against the hand
  // Let go and wait: still latched, and the scene's commands are ignored.
  device->set_hand({});
  for (int k = 0; k < 200; ++k) device.write({{5.0, 5.0, 5.0}}, kT);
  EXPECT_TRUE(device.model.watchdog_tripped());
  EXPECT_EQ(device->last_command().motor, (std::array<double, 3>{0.0, 0.0, 0.0}));
  ASSERT_TRUE(device.model.rearm());
  EXPECT_FALSE(device.model.watchdog_tripped());
  EXPECT_FALSE(device.model.in_safe_state());
  device.write({{1.0, 0.0, 0.0}}, kT);
  EXPECT_GT(device->last_command().motor[0], 0.0);
  EXPECT_EQ(device->last_command().brake[0], 0.0);
}

// A tripped device reports its safe state in every reading (so the loop flags a device fault and
// clients get the event), and re-arms itself once it has been still for rearm_after_s.
TEST(SimulatedJoystickDevice, ReportsItsSafeStateAndReArmsAfterRest_L1955) {
  SimulatedJoystickConfig config;
  config.initial = {-0.6, 0.0, 0.24};
  config.rearm_after_s = 0.1;
  Joystick device(JoystickModel(config.model()), config);
  device->set_hand(push({25.0, 0.0, 0.0}));
  ToolReading r;
  int k = 0;
  for (; k < 300 && !device.model.watchdog_tripped(); ++k) device.write({}, kT);
  ASSERT_TRUE(device.model.watchdog_tripped());
  ASSERT_EQ(device.read(r), DeviceStatus::kOk);
  EXPECT_TRUE(r.safe_state);
  device->set_hand({});
  int rearmed_after = -1;
  for (int n = 1; n <= 500 && rearmed_after < 0; ++n) {
    device.write({}, kT);
    if (!device.model.in_safe_state()) rearmed_after = n;
  }
  std::printf("  re-armed %d ticks after the hand let go\n", rearmed_after);
  ASSERT_GT(rearmed_after, 0);
  EXPECT_GE(rearmed_after, 100);  // 0.1 s of rest first
  EXPECT_LE(rearmed_after, 150);  // the brakes stop it at once
  ASSERT_EQ(device.read(r), DeviceStatus::kOk);
  EXPECT_FALSE(r.safe_state);

  config.rearm_after_s = -1.0;
  EXPECT_EQ(config.validate().rfind("rearm_after_s:", 0), 0u);
}

TEST(SimulatedJoystickDevice, EnterSafeStateZeroesMotorsAndSetsBrakes) {
  const SimulatedJoystickConfig config;
  Joystick device(JoystickModel(config.model()), config);
  device.port.enter_safe_state();
  ASSERT_EQ(device.write({{3.0, 3.0, 3.0}}, kT), DeviceStatus::kOk);
  const engine::GimbalJoystickParams& p = config.params;
  EXPECT_EQ(device->last_command().motor, (std::array<double, 3>{0.0, 0.0, 0.0}));
  EXPECT_EQ(device->last_command().brake,
            (std::array<double, 3>{p.brake_limit_gimbal, p.brake_limit_gimbal, p.brake_limit_shaft}));
  EXPECT_TRUE(device.model.in_safe_state());
  EXPECT_FALSE(device.model.watchdog_tripped());
  ASSERT_TRUE(device.model.rearm());
  // A non-finite command is a fault too.
  device.write({{std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0}}, kT);
  EXPECT_TRUE(device.model.in_safe_state());
  EXPECT_EQ(device->last_command().motor, (std::array<double, 3>{0.0, 0.0, 0.0}));
  ToolReading r;
  EXPECT_EQ(device.read(r), DeviceStatus::kOk);  // the state itself is fine
}

TEST(SimulatedJoystickDevice, ANonFiniteStateIsAnErrorAndCannotBeRearmed) {
  const SimulatedJoystickConfig config;
  Joystick device(JoystickModel(config.model()), config);
  device->set_hand(push({std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0}));
  EXPECT_EQ(device.write({}, kT), DeviceStatus::kError);
  EXPECT_TRUE(device.model.in_safe_state());
  ToolReading r;
  EXPECT_EQ(device.read(r), DeviceStatus::kError);
  EXPECT_FALSE(device.model.rearm());
  EXPECT_TRUE(device.model.in_safe_state());
}

TEST(SimulatedJoystickDevice, RunsAreExactlyReproducible) {
  const SimulatedJoystickConfig config;
  Joystick a(JoystickModel(config.model()), config), b(JoystickModel(config.model()), config);
  const engine::HandInput hand = push({3.0, -2.0, 8.0});
  a->set_hand(hand);
  b->set_hand(hand);
  ToolReading ra, rb;
  for (int k = 0; k < 500; ++k) {
    a.read(ra);
    b.read(rb);
    ASSERT_EQ(ra.p_WT, rb.p_WT);
    a.write({-2.0 * ra.v_WT}, kT);
    b.write({-2.0 * rb.v_WT}, kT);
  }
  EXPECT_GT(engine::norm(ra.p_WT - engine::joystick_forward(config.initial)), 1e-3);
}

}  // namespace
}  // namespace haptic::runtime
