// The simulated operator: force profiles and target trajectories against their closed forms, the
// grip presets, and a hand driving the simulated device (its mass moving with the tool).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "engine/operator/simulated_hand.hpp"
#include "runtime/cartesian_model.hpp"
#include "runtime/simulated_point_mass_device.hpp"
#include "support/modelled_device.hpp"

namespace haptic::runtime {
namespace {

using engine::ForceProfile;
using engine::HandInput;
using engine::TargetTrajectory;
using engine::Vec3;

HandInput push(Vec3 force, ForceProfile profile) {
  HandInput hand;
  hand.mode = HandInput::Mode::kApplyForce;
  hand.force = force;
  hand.profile = profile;
  return hand;
}

TEST(ForceProfile, StepRampAndSineFollowTheirDefinitions) {
  const Vec3 F{0.0, 0.0, -5.0};
  const HandInput step = push(F, {ForceProfile::Shape::kStep, 0.5, 0.0, 0.0, {}, {}});
  EXPECT_EQ(engine::profile_force(step, 0.499).z, 0.0);
  EXPECT_EQ(engine::profile_force(step, 0.5).z, -5.0);

  const HandInput ramp = push(F, {ForceProfile::Shape::kRamp, 0.1, 0.4, 0.0, {}, {}});
  EXPECT_EQ(engine::profile_force(ramp, 0.05).z, 0.0);
  EXPECT_DOUBLE_EQ(engine::profile_force(ramp, 0.2).z, -1.25);  // a quarter of the way up
  EXPECT_EQ(engine::profile_force(ramp, 0.6).z, -5.0);

  const HandInput sine = push(F, {ForceProfile::Shape::kSine, 0.0, 0.0, 2.0, {0.0, 0.0, -1.0}, {}});
  EXPECT_NEAR(engine::profile_force(sine, 0.125).z, -1.0 - 5.0, 1e-12);  // sin(π/2)
  EXPECT_NEAR(engine::profile_force(sine, 0.25).z, -1.0, 1e-12);

  EXPECT_EQ(engine::profile_force(push(F, {}), 123.0).z, -5.0);  // constant
}

TEST(ForceProfile, RecordedInterpolatesHoldsItsLastSampleOrRepeats) {
  ForceProfile profile;
  profile.shape = ForceProfile::Shape::kRecorded;
  profile.recorded.count = 3;
  profile.recorded.sample_period_s = 0.1;
  profile.recorded.samples[0] = {0.0, 0.0, 0.0};
  profile.recorded.samples[1] = {0.0, 0.0, -2.0};
  profile.recorded.samples[2] = {1.0, 0.0, -4.0};
  HandInput hand = push({9.0, 9.0, 9.0}, profile);  // the amplitude does not scale a recording
  EXPECT_EQ(engine::profile_force(hand, 0.0).z, 0.0);
  EXPECT_NEAR(engine::profile_force(hand, 0.05).z, -1.0, 1e-12);
  EXPECT_NEAR(engine::profile_force(hand, 0.15).x, 0.5, 1e-12);
  EXPECT_EQ(engine::profile_force(hand, 0.2).z, -4.0);
  EXPECT_EQ(engine::profile_force(hand, 7.0).z, -4.0);  // holds the last sample
  hand.profile.recorded.repeat = true;  // period 0.3 s, the last sample blends into the first
  EXPECT_NEAR(engine::profile_force(hand, 0.25).z, -2.0, 1e-12);
  EXPECT_NEAR(engine::profile_force(hand, 0.35).z, -1.0, 1e-12);
  EXPECT_NEAR(engine::profile_force(hand, 3.05).z, -1.0, 1e-9);
  hand.profile.recorded.count = 0;
  EXPECT_EQ(engine::profile_force(hand, 0.1), Vec3{});
}

TEST(TargetTrajectory, LineAndSineGivePositionAndVelocity) {
  HandInput hand;
  hand.mode = HandInput::Mode::kFollowTarget;
  hand.target = {0.0, 0.0, 0.02};
  hand.trajectory.shape = TargetTrajectory::Shape::kLine;
  hand.trajectory.end = {0.0, 0.0, -0.01};
  hand.trajectory.duration_s = 2.0;
  Vec3 x, v;
  engine::target_at(hand, 1.0, x, v);
  EXPECT_DOUBLE_EQ(x.z, 0.005);
  EXPECT_DOUBLE_EQ(v.z, -0.015);
  engine::target_at(hand, 3.0, x, v);
  EXPECT_EQ(x.z, -0.01);
  EXPECT_EQ(v.z, 0.0);

  hand.trajectory = {TargetTrajectory::Shape::kSine, {}, 0.0, {0.01, 0.0, 0.0}, 0.5};
  engine::target_at(hand, 0.5, x, v);  // a quarter period
  EXPECT_NEAR(x.x, 0.01, 1e-15);
  EXPECT_NEAR(v.x, 0.0, 1e-15);
  engine::target_at(hand, 0.0, x, v);
  EXPECT_NEAR(v.x, 0.01 * std::numbers::pi, 1e-15);
  // The hand's damper acts on the velocity relative to the moving target.
  hand.stiffness = 0.0;
  hand.damping = 10.0;
  EXPECT_NEAR(engine::hand_force(hand, {}, {}, 0.0).x, 10.0 * 0.01 * std::numbers::pi, 1e-12);
}

/// The point mass with its model, driven at its tool point; starts at rest at z = z0 (m).
struct PointMass : Modelled<SimulatedPointMassDevice, CartesianModel> {
  explicit PointMass(double z0)
      : Modelled(CartesianModel{}, engine::PointMassParams{},
                 engine::PointMassState{{0.0, 0.0, z0}, {}}, 20.0) {}
};

/// Runs the device for `seconds` with zero device force; returns the final reading.
ToolReading run(PointMass& device, double seconds) {
  ToolReading reading;
  for (int k = 0; k < static_cast<int>(std::lround(seconds * 1000.0)); ++k) {
    device.write(ToolCommand{}, 0.001);
  }
  device.read(reading);
  return reading;
}

TEST(SimulatedOperator, TightGripTracksALineAndLooseGripLagsIt) {
  auto follow = [](engine::Grip grip) {
    HandInput hand;
    hand.mode = HandInput::Mode::kFollowTarget;
    hand.target = {0.0, 0.0, 0.02};
    hand.trajectory.shape = TargetTrajectory::Shape::kLine;
    hand.trajectory.end = {0.0, 0.0, -0.01};
    hand.trajectory.duration_s = 1.0;
    hand.mass = grip.mass;
    hand.stiffness = grip.stiffness;
    hand.damping = grip.damping;
    return hand;
  };
  PointMass tight_device(0.02);
  tight_device->set_hand(follow(engine::kTightGrip));
  PointMass loose_device(0.02);
  loose_device->set_hand(follow(engine::kLooseGrip));
  // Halfway (0.5 s) the target is at 5 mm. The tight grip (ω = 20 rad/s, ζ = 0.19) is within a
  // millimetre of it; the loose one (overdamped, slow pole at −0.69 1/s) trails further behind.
  const double tight_error = std::abs(run(tight_device, 0.5).p_WT.z - 0.005);
  const double loose_error = std::abs(run(loose_device, 0.5).p_WT.z - 0.005);
  EXPECT_LT(tight_error, 0.001);
  EXPECT_GT(loose_error, tight_error);
  // Long after, both rest on the end point (the loose grip's slow pole needs ~10 time constants).
  EXPECT_NEAR(run(tight_device, 5.0).p_WT.z, -0.01, 1e-5);
  EXPECT_NEAR(run(loose_device, 20.0).p_WT.z, -0.01, 1e-5);
}

TEST(SimulatedOperator, HandMassMovesWithTheToolOnlyWhileHolding) {
  // The same device force gives a 2.01 kg tool 201 times less acceleration than the bare 0.01 kg.
  PointMass held(0.0);
  HandInput hand;
  hand.mode = HandInput::Mode::kFollowTarget;
  hand.mass = 2.0;  // no spring, no damper: just the hand's inertia
  held->set_hand(hand);
  PointMass bare(0.0);
  for (int k = 0; k < 10; ++k) {
    held.write(ToolCommand{{1.0, 0.0, 0.0}}, 0.001);
    bare.write(ToolCommand{{1.0, 0.0, 0.0}}, 0.001);
  }
  ToolReading a, b;
  held.read(a);
  bare.read(b);
  // v(t) = (F/b)(1 − e^{−b t/m}) for each total mass (Eom et al. eq. 5 plant).
  const double b_device = engine::PointMassParams{}.damping;
  auto v = [&](double m) { return 1.0 / b_device * -std::expm1(-b_device * 0.01 / m); };
  EXPECT_NEAR(a.v_WT.x, v(2.01), 1e-12);
  EXPECT_NEAR(b.v_WT.x, v(0.01), 1e-12);
  // Released, the hand's mass no longer counts.
  held->set_hand(HandInput{});
  held.write(ToolCommand{}, 0.001);
  EXPECT_NEAR(held.read(a) == DeviceStatus::kOk ? a.v_WT.x : 0.0,
              v(2.01) * std::exp(-b_device * 0.001 / 0.01), 1e-12);
}

TEST(SimulatedOperator, ProfileTimeStartsWhenTheInputArrives) {
  PointMass device(0.0);
  run(device, 1.0);  // time passes before the input is set
  device->set_hand(push({0.0, 0.0, 1.0}, {ForceProfile::Shape::kStep, 0.1, 0.0, 0.0, {}, {}}));
  EXPECT_EQ(run(device, 0.09).v_WT.z, 0.0);  // the step is 0.1 s after the input, not after start
  EXPECT_GT(run(device, 0.02).v_WT.z, 0.0);
}

TEST(SimulatedOperator, ARecordedPushDrivesTheToolAndANewInputReplacesIt) {
  PointMass device(0.0);
  ForceProfile profile;
  profile.shape = ForceProfile::Shape::kRecorded;
  profile.recorded.count = 2;
  profile.recorded.sample_period_s = 0.05;
  profile.recorded.samples[0] = {0.0, 0.0, 0.01};  // small: the 10 g mass stays in its workspace
  profile.recorded.samples[1] = {0.0, 0.0, 0.01};
  device->set_hand(push({}, profile));
  EXPECT_GT(run(device, 0.05).v_WT.z, 0.0);
  device->set_hand(push({0.0, 0.0, -0.03}, {}));  // a constant push the other way
  const double before = run(device, 0.0).v_WT.z;
  EXPECT_LT(run(device, 0.05).v_WT.z, before);
}

}  // namespace
}  // namespace haptic::runtime
