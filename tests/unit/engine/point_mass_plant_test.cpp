// The default device's plant, m x'' + b x' = F per axis (Eom, Suh, Yi, eq. 5; m = 0.01 kg,
// b = 0.022 N·s/m from their experiment), against its closed-form solutions.
#include <gtest/gtest.h>

#include <cmath>

#include "engine/device/point_mass_plant.hpp"
#include "engine/operator/simulated_hand.hpp"

namespace haptic::engine {
namespace {

constexpr double kMass = 0.01;
constexpr double kDamping = 0.022;
constexpr double kDt = 0.001;

PointMassParams params(std::uint32_t substeps, double damping = kDamping) {
  PointMassParams p;
  p.mass = kMass;
  p.damping = damping;
  p.substeps = substeps;
  p.workspace_min = {-100, -100, -100};
  p.workspace_max = {100, 100, 100};
  return p;
}

auto no_external = [](const Vec3&, const Vec3&) { return Vec3{}; };

/// x(t) from rest under constant F: (F/b) t − (F m / b²)(1 − e^{−bt/m}).
double exact_position(double F, double t) {
  return F / kDamping * t - F * kMass / (kDamping * kDamping) * (1.0 - std::exp(-kDamping * t / kMass));
}

class ConstantForce : public ::testing::TestWithParam<std::uint32_t> {};

TEST_P(ConstantForce, MatchesTheExactSolutionToRoundOff) {
  PointMassPlant plant(params(GetParam()));
  const Vec3 F{1.0, -2.0, 0.5};
  for (int k = 1; k <= 1000; ++k) {
    plant.step(F, kDt, no_external);
    const double t = k * kDt;
    // Relative to the size of the closed form's own terms (F t / b), which cancel early on.
    ASSERT_NEAR(plant.state().p_WT.x, exact_position(F.x, t), 1e-12 * std::abs(F.x / kDamping * t));
    ASSERT_NEAR(plant.state().p_WT.y, exact_position(F.y, t), 1e-12 * std::abs(F.y / kDamping * t));
  }
  // Terminal velocity F/b is approached: v(1 s) = (F/b)(1 − e^{−2.2}).
  EXPECT_NEAR(plant.state().v_WT.x, F.x / kDamping * (1.0 - std::exp(-2.2)), 1e-9);
}
INSTANTIATE_TEST_SUITE_P(Substeps, ConstantForce, ::testing::Values(1u, 10u));

TEST(PointMassPlant, UndampedMassIsExactParabola) {
  PointMassPlant plant(params(3, 0.0));
  for (int k = 0; k < 500; ++k) plant.step({0.0, 0.0, 2.0}, kDt, no_external);
  const double t = 0.5;
  EXPECT_NEAR(plant.state().p_WT.z, 2.0 * t * t / (2.0 * kMass), 1e-9);
  EXPECT_NEAR(plant.state().v_WT.z, 2.0 * t / kMass, 1e-9);
}

TEST(PointMassPlant, FreeMotionDecaysExponentially) {
  PointMassPlant plant(params(1), PointMassState{{}, {0.1, 0.0, 0.0}});
  for (int k = 0; k < 200; ++k) plant.step({}, kDt, no_external);
  EXPECT_NEAR(plant.state().v_WT.x, 0.1 * std::exp(-kDamping / kMass * 0.2), 1e-14);
}

TEST(PointMassPlant, StopsInelasticallyAtTheWorkspaceBox) {
  PointMassParams p = params(10);
  p.workspace_min = {-0.1, -0.1, -0.1};
  p.workspace_max = {0.1, 0.1, 0.1};
  PointMassPlant plant(p);
  for (int k = 0; k < 2000; ++k) plant.step({0.0, 0.0, -1.0}, kDt, no_external);
  EXPECT_EQ(plant.state().p_WT.z, -0.1);
  EXPECT_EQ(plant.state().v_WT.z, 0.0);
  plant.step({0.0, 0.0, 1.0}, kDt, no_external);  // and leaves it when pushed back
  EXPECT_GT(plant.state().p_WT.z, -0.1);
}

TEST(SimulatedHand, FollowTargetSettlesOnTheTarget) {
  PointMassPlant plant(params(10));
  HandInput hand;
  hand.mode = HandInput::Mode::kFollowTarget;
  hand.target = {0.01, -0.02, 0.03};
  hand.stiffness = 200.0;
  hand.damping = 2.0;
  for (int k = 0; k < 2000; ++k) {
    plant.step({}, kDt, [&](const Vec3& p, const Vec3& v) { return hand_force(hand, p, v); });
  }
  EXPECT_NEAR(plant.state().p_WT.x, 0.01, 1e-9);
  EXPECT_NEAR(plant.state().p_WT.y, -0.02, 1e-9);
  EXPECT_NEAR(plant.state().p_WT.z, 0.03, 1e-9);
  EXPECT_EQ(hand_force(HandInput{}, {1, 2, 3}, {4, 5, 6}), Vec3{});
}

/// |x| at the end of 2 s of the plant held by a spring-damper hand, sampled per sub-step.
double final_amplitude(double stiffness, double damping, std::uint32_t substeps) {
  PointMassPlant plant(params(substeps, 0.0), PointMassState{{0.0, 0.0, 0.001}, {}});
  HandInput hand;
  hand.mode = HandInput::Mode::kFollowTarget;
  hand.stiffness = stiffness;
  hand.damping = damping;
  double peak_late = 0.0;
  for (int k = 0; k < 2000; ++k) {
    plant.step({}, kDt, [&](const Vec3& p, const Vec3& v) { return hand_force(hand, p, v); });
    if (k >= 1900) peak_late = std::max(peak_late, std::abs(plant.state().p_WT.z));
  }
  return peak_late;
}

// The hand's force is held over each sub-step (explicit in the hand, exact in the plant). For an
// undamped spring hand the step map [[1 − ω²h²/2, h], [−ω²h, 1]] has determinant 1 + ω²h²/2, so
// the amplitude grows by about ω²h²/4 per sub-step: e^{N ω² h² / 4} after N sub-steps. With the
// defaults (K = 200 N/m, m = 0.01 kg, h = 0.1 ms) that is e^{1} over 2 s; some hand damping removes
// it; 1 sub-step of a 1e5 N/m hand (ωh = 3.2) diverges outright.
TEST(SimulatedHand, HeldForceGainsEnergyAtThePredictedRateAndDampingRemovesIt) {
  const double omega_h = std::sqrt(200.0 / kMass) * kDt / 10.0;
  const double predicted = 0.001 * std::exp(20000.0 * omega_h * omega_h / 4.0);
  EXPECT_NEAR(final_amplitude(200.0, 0.0, 10), predicted, 0.02 * predicted);
  EXPECT_LT(final_amplitude(200.0, 2.0, 10), 1e-6);    // the examples' hand: settles
  EXPECT_GT(final_amplitude(1e5, 0.0, 1), 1.0);        // diverged to the ±100 m test box
}

}  // namespace
}  // namespace haptic::engine
