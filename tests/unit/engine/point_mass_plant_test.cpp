// The default device's plant, m x'' + b x' = F per axis (Eom, Suh, Yi, eq. 5; m = 0.01 kg,
// b = 0.022 N·s/m from their experiment), against its closed-form solutions, and the simulated
// hand that drives it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "engine/device/point_mass_plant.hpp"
#include "engine/operator/simulated_hand.hpp"

namespace haptic::engine {
namespace {

constexpr double kMass = 0.01;      // kg (Eom et al.)
constexpr double kDamping = 0.022;  // N·s/m (Eom et al.)
constexpr double kDt = 0.001;       // s, the 1 kHz tick

PointMassParams params(std::uint32_t substeps, double damping = kDamping) {
  PointMassParams p;
  p.mass = kMass;
  p.damping = damping;
  p.substeps = substeps;
  p.workspace_min = {-100, -100, -100};  // far away unless a test is about the box
  p.workspace_max = {100, 100, 100};
  return p;
}

constexpr auto kNoHand = [](const Vec3&, const Vec3&) { return Vec3{}; };

/// x(t) from rest under constant F: (F/b) t − (F m / b²)(1 − e^{−bt/m}), in long double with
/// expm1 so the reference is far more accurate than the 1e-12 asked of the plant.
long double exact_position(long double F, long double t, long double b = kDamping) {
  const long double m = kMass;
  return F / b * t + F * m / (b * b) * std::expm1(-b * t / m);
}

/// v(t) from rest under constant F: (F/b)(1 − e^{−bt/m}).
long double exact_velocity(long double F, long double t) {
  const long double m = kMass;
  const long double b = kDamping;
  return -F / b * std::expm1(-b * t / m);
}

void expect_relative(double actual, long double expected, double tolerance) {
  EXPECT_LE(std::abs(static_cast<long double>(actual) - expected),
            tolerance * std::abs(expected))
      << "actual " << actual << " expected " << static_cast<double>(expected);
}

class ConstantForceFromRest : public ::testing::TestWithParam<std::uint32_t> {};

// Exact per-substep integration: the sub-step count must not matter for a constant force.
TEST_P(ConstantForceFromRest, MatchesTheClosedFormTo1e12Relative) {
  PointMassPlant plant(params(GetParam()));
  const Vec3 F{1.0, -2.0, 0.5};  // N
  for (int k = 1; k <= 1000; ++k) {
    plant.step(F, kDt, kNoHand);
    const long double t = k * static_cast<long double>(kDt);
    expect_relative(plant.state().p_WT.x, exact_position(F.x, t), 1e-12);
    expect_relative(plant.state().p_WT.y, exact_position(F.y, t), 1e-12);
    expect_relative(plant.state().p_WT.z, exact_position(F.z, t), 1e-12);
    expect_relative(plant.state().v_WT.x, exact_velocity(F.x, t), 1e-12);
    if (HasFailure()) FAIL() << "at tick " << k;
  }
}
INSTANTIATE_TEST_SUITE_P(Substeps, ConstantForceFromRest, ::testing::Values(1u, 10u));

TEST(PointMassPlant, UndampedMassFollowsTheParabolaExactly) {
  for (const std::uint32_t substeps : {1u, 10u}) {
    PointMassPlant plant(params(substeps, 0.0));
    for (int k = 1; k <= 1000; ++k) {
      plant.step({0.0, 0.0, 0.01}, kDt, kNoHand);
      const double t = k * kDt;
      expect_relative(plant.state().p_WT.z, 0.01 * t * t / (2.0 * kMass), 1e-12);  // F t²/(2m)
      expect_relative(plant.state().v_WT.z, 0.01 * t / kMass, 1e-12);
    }
    EXPECT_EQ(plant.state().p_WT.x, 0.0);
  }
}

TEST(PointMassPlant, FreeMotionDecaysExponentially) {
  const double v0 = 0.1;  // m/s
  PointMassPlant plant(params(1), PointMassState{{}, {v0, 0.0, 0.0}});
  for (int k = 1; k <= 1000; ++k) {
    plant.step({}, kDt, kNoHand);
    const long double t = k * static_cast<long double>(kDt);
    const long double decay = std::exp(-static_cast<long double>(kDamping) / kMass * t);
    expect_relative(plant.state().v_WT.x, v0 * decay, 1e-12);  // v0 e^{−bt/m}
    expect_relative(plant.state().p_WT.x, v0 * kMass / kDamping * (1.0L - decay), 1e-12);
  }
}

TEST(PointMassPlant, TinyDampingLosesNoDigitsToCancellation) {
  // b = 1e-6 N·s/m: b h / m = 1e-8 per sub-step, where the textbook form
  // x0 + (F/b) h + (v0 − F/b)(1 − e^{−ah})/a cancels two terms ~1e8 times larger than the step.
  constexpr double kTinyDamping = 1e-6;
  PointMassPlant plant(params(10, kTinyDamping));
  for (int k = 1; k <= 1000; ++k) {
    plant.step({0.001, 0.0, 0.0}, kDt, kNoHand);
    const long double t = k * static_cast<long double>(kDt);
    expect_relative(plant.state().p_WT.x, exact_position(0.001, t, kTinyDamping), 1e-12);
  }
}

TEST(PointMassPlant, StopsInelasticallyAtEveryFaceOfTheWorkspaceBox) {
  PointMassParams p = params(10);
  p.workspace_min = {-0.1, -0.2, -0.3};
  p.workspace_max = {0.1, 0.2, 0.3};
  for (const double sign : {-1.0, 1.0}) {
    PointMassPlant plant(p);
    for (int k = 0; k < 2000; ++k) plant.step(Vec3{1.0, 1.0, 1.0} * sign, kDt, kNoHand);
    EXPECT_EQ(plant.state().p_WT, (Vec3{0.1, 0.2, 0.3} * sign));
    EXPECT_EQ(plant.state().v_WT, Vec3{});
    // Pushed back inwards, it leaves the bound at once.
    plant.step(Vec3{1.0, 1.0, 1.0} * -sign, kDt, kNoHand);
    EXPECT_LT(std::abs(plant.state().p_WT.x), 0.1);
    EXPECT_LT(plant.state().v_WT.x * sign, 0.0);
  }
  // Only the outward component is stopped: sliding along a face keeps its tangential velocity.
  PointMassPlant plant(p, PointMassState{{0.1, 0.0, 0.0}, {0.5, 0.25, 0.0}});
  plant.step({}, kDt, kNoHand);
  EXPECT_EQ(plant.state().p_WT.x, 0.1);
  EXPECT_EQ(plant.state().v_WT.x, 0.0);
  EXPECT_GT(plant.state().v_WT.y, 0.0);
}

TEST(PointMassPlant, CoulombFrictionHoldsItUnderItsForceAndStopsItExactlyWhereItsVelocityVanishes) {
  PointMassParams p = params(10);
  p.coulomb = 0.5;
  PointMassPlant plant(p);
  // Under the friction's force, it never moves; above it, it moves as a mass-damper under F − c.
  for (int k = 0; k < 100; ++k) plant.step({0.5, -0.4, 0.0}, kDt, kNoHand);
  EXPECT_EQ(plant.state().p_WT.x, 0.0);
  EXPECT_EQ(plant.state().p_WT.y, 0.0);
  for (int k = 0; k < 100; ++k) plant.step({0.8, 0.0, 0.0}, kDt, kNoHand);
  EXPECT_NEAR(plant.state().p_WT.x, static_cast<double>(exact_position(0.3L, 0.1L)), 1e-12);
  // Let go at v0, friction alone brings it to rest: without damping at v0²/(2c/m), exactly, and
  // it stays there.
  p.damping = 0.0;
  PointMassPlant coasting(p, {{}, {0.2, 0.0, 0.0}});
  for (int k = 0; k < 20; ++k) coasting.step({}, kDt, kNoHand);
  EXPECT_NEAR(coasting.state().p_WT.x, 0.2 * 0.2 / (2.0 * 0.5 / kMass), 1e-15);
  EXPECT_EQ(coasting.state().v_WT.x, 0.0);
  // With damping: at v∞ t* + (m/b) v0, v∞ = −c/b, e^{−bt*/m} = −v∞/(v0 − v∞).
  p.damping = kDamping;
  PointMassPlant damped(p, {{}, {0.2, 0.0, 0.0}});
  for (int k = 0; k < 20; ++k) damped.step({}, kDt, kNoHand);
  const double terminal = -0.5 / kDamping;
  const double stop = kMass / kDamping * std::log((0.2 - terminal) / -terminal);
  EXPECT_NEAR(damped.state().p_WT.x, terminal * stop + kMass / kDamping * 0.2, 1e-13);
  EXPECT_EQ(damped.state().v_WT.x, 0.0);
}

TEST(PointMassPlant, AnActuatorsLagDelaysTheForceAsAFirstOrderFilter) {
  // A step F through 1/(1 + sτ) on an undamped mass: x(t) = (F/m) (t²/2 − τ t + τ² (1 − e^{−t/τ})).
  PointMassParams p = params(10, 0.0);
  p.actuator_lag = 8.8e-3;
  PointMassPlant plant(p);
  for (int k = 0; k < 50; ++k) plant.step({1.0, 0.0, 0.0}, kDt, kNoHand);
  const double t = 0.05, tau = 8.8e-3;
  const double exact = 1.0 / kMass * (t * t / 2.0 - tau * t + tau * tau * (1.0 - std::exp(-t / tau)));
  // The lag's mean over each sub-step drives the mass as a held force: second order in the sub-step.
  EXPECT_NEAR(plant.state().p_WT.x, exact, 1e-4 * exact);
  EXPECT_LT(plant.state().p_WT.x, 1.0 / kMass * t * t / 2.0 * 0.8);  // well behind the unlagged
}

TEST(SimulatedHand, ForceLawPerMode) {
  HandInput hand;
  EXPECT_EQ(hand_force(hand, {1, 2, 3}, {4, 5, 6}), Vec3{});  // kNone lets go
  hand.mode = HandInput::Mode::kApplyForce;
  hand.force = {0.5, -1.0, 2.0};
  EXPECT_EQ(hand_force(hand, {1, 2, 3}, {4, 5, 6}), (Vec3{0.5, -1.0, 2.0}));
  hand.mode = HandInput::Mode::kFollowTarget;
  hand.target = {0.01, 0.0, 0.0};
  hand.stiffness = 200.0;
  hand.damping = 2.0;
  // 200 N/m × 1 cm − 2 N·s/m × 0.5 m/s.
  EXPECT_DOUBLE_EQ(hand_force(hand, {0.0, 0.0, 0.0}, {0.5, 0.0, 0.0}).x, 1.0);
}

TEST(SimulatedHand, FollowTargetSettlesOnTheTarget) {
  PointMassPlant plant(params(10));
  HandInput hand;
  hand.mode = HandInput::Mode::kFollowTarget;
  hand.target = {0.01, -0.02, 0.03};
  hand.stiffness = 200.0;  // N/m
  hand.damping = 2.0;      // N·s/m
  const auto on_tool = [&](const Vec3& p, const Vec3& v) { return hand_force(hand, p, v); };
  for (int k = 0; k < 100; ++k) plant.step({}, kDt, on_tool);
  // Poles of m s² + (b + B) s + K: real part −(b + B)/(2m) ≈ −101 /s, so 0.1 s is e^{−10}.
  EXPECT_NEAR(plant.state().p_WT.y, -0.02, 0.02 * 1e-3);
  for (int k = 0; k < 1900; ++k) plant.step({}, kDt, on_tool);
  EXPECT_NEAR(plant.state().p_WT.x, 0.01, 1e-12);
  EXPECT_NEAR(plant.state().p_WT.y, -0.02, 1e-12);
  EXPECT_NEAR(plant.state().p_WT.z, 0.03, 1e-12);
  EXPECT_NEAR(norm(plant.state().v_WT), 0.0, 1e-12);
}

// The hand's force is sampled at the start of each sub-step and held (the plant itself is exact),
// so a hand spring K with damper B on the plant (m, b) and sub-step h is a sampled loop. The
// one-sub-step map's spectral radius, checked numerically for K = 44 … 1e5 N/m, gives:
//   b = B = 0:  rho = sqrt(1 + (h sqrt(K/m))² / 2) > 1 for every h: the held spring always
//               gains energy, by (1 + K h² / (2m)) per sub-step.
//   otherwise:  stable iff K h < 2 (b + B) (to within 1 %; exact for b = 0) and B h < 2 m.
// For the Eom plant at the default h = 1 ms / 10 this puts the limit of an undamped hand spring
// at K = 440 N/m, and of one with B = 2 N·s/m at about 40,000 N/m.

struct HeldSpringRun {
  double initial;  // |x| at the start. Unit: m.
  double final_peak;  // Largest |x| over the last tenth of the run. Unit: m.
};

/// One axis pulled back to 0 by a FOLLOW_TARGET hand, from x = 1 mm at rest.
HeldSpringRun run_held_spring(double stiffness, double hand_damping, double plant_damping,
                              double h, std::uint32_t substeps, int ticks) {
  PointMassPlant plant(params(substeps, plant_damping), PointMassState{{0.001, 0.0, 0.0}, {}});
  HandInput hand;
  hand.mode = HandInput::Mode::kFollowTarget;
  hand.stiffness = stiffness;
  hand.damping = hand_damping;
  const auto on_tool = [&](const Vec3& p, const Vec3& v) { return hand_force(hand, p, v); };
  HeldSpringRun run{0.001, 0.0};
  for (int k = 0; k < ticks; ++k) {
    plant.step({}, h * substeps, on_tool);
    if (k >= ticks - ticks / 10) {
      run.final_peak = std::max(run.final_peak, std::abs(plant.state().p_WT.x));
    }
  }
  return run;
}

TEST(SimulatedHand, UndampedHeldSpringOnUndampedPlantGainsEnergyAtAnySubstep) {
  // With b = B = 0 the sub-step map is [[1 − K h²/(2m), h], [−K h/m, 1]], determinant
  // 1 + K h²/(2m). The phase-plane area spanned by two solutions, x_a v_b − x_b v_a, is
  // multiplied by exactly that at every sub-step.
  constexpr double kStiffness = 200.0;  // N/m
  for (const std::uint32_t substeps : {10u, 100u}) {
    const double h = kDt / substeps;
    HandInput hand;
    hand.mode = HandInput::Mode::kFollowTarget;
    hand.stiffness = kStiffness;
    const auto on_tool = [&](const Vec3& p, const Vec3& v) { return hand_force(hand, p, v); };
    PointMassPlant a(params(substeps, 0.0), PointMassState{{0.001, 0.0, 0.0}, {}});
    PointMassPlant b(params(substeps, 0.0), PointMassState{{}, {0.1, 0.0, 0.0}});
    const int ticks = 2000;
    for (int k = 0; k < ticks; ++k) {
      a.step({}, kDt, on_tool);
      b.step({}, kDt, on_tool);
    }
    const double area = a.state().p_WT.x * b.state().v_WT.x - b.state().p_WT.x * a.state().v_WT.x;
    const double growth =
        std::pow(1.0 + kStiffness * h * h / (2.0 * kMass), static_cast<double>(ticks) * substeps);
    EXPECT_NEAR(area / (0.001 * 0.1), growth, 1e-9 * growth) << substeps << " sub-steps";
    EXPECT_GT(growth, 1.2);  // e^{2} at 10 sub-steps, e^{0.2} at 100: finer only slows it
  }
  // The area grows as the amplitude squared: over 2 s at 10 sub-steps the swing grows about e^1.
  const HeldSpringRun run = run_held_spring(kStiffness, 0.0, 0.0, 1e-4, 10, 2000);
  EXPECT_GT(run.final_peak, 2.6 * run.initial);
  EXPECT_LT(run.final_peak, 2.75 * run.initial);
}

TEST(SimulatedHand, UndampedHeldSpringOnEomPlantIsStableBelowKhEqualsTwoB) {
  // Default sub-step h = 0.1 ms: the limit is K = 2 b / h = 440 N/m.
  const HeldSpringRun below = run_held_spring(400.0, 0.0, kDamping, 1e-4, 10, 5000);
  EXPECT_LT(below.final_peak, below.initial);
  const HeldSpringRun above = run_held_spring(480.0, 0.0, kDamping, 1e-4, 10, 5000);
  EXPECT_GT(above.final_peak, above.initial);
  // One sub-step per 1 ms tick moves the limit ten-fold lower, to 44 N/m.
  EXPECT_LT(run_held_spring(40.0, 0.0, kDamping, 1e-3, 1, 20000).final_peak, 0.001);
  EXPECT_GT(run_held_spring(48.0, 0.0, kDamping, 1e-3, 1, 20000).final_peak, 0.001);
}

TEST(SimulatedHand, DampedHeldSpringStableAtOmegaHOneDivergesPastTheDamperLimit) {
  // K = 200 N/m, B = 2 N·s/m: here B h < 2 m binds first, at h = 10 ms, omega h = 1.41.
  const double omega = std::sqrt(200.0 / kMass);  // rad/s
  const HeldSpringRun at_1 = run_held_spring(200.0, 2.0, kDamping, 1.0 / omega, 1, 200);
  EXPECT_LT(at_1.final_peak, 1e-12);  // spectral radius 0.28 per sub-step
  const HeldSpringRun at_1_5 = run_held_spring(200.0, 2.0, kDamping, 1.5 / omega, 1, 200);
  EXPECT_GT(at_1_5.final_peak, 1.0);  // 1.25 per sub-step, and it hits the ±100 m box
  const HeldSpringRun at_2_5 = run_held_spring(200.0, 2.0, kDamping, 2.5 / omega, 1, 200);
  EXPECT_GT(at_2_5.final_peak, 1.0);
  // A stiff hand (K = 1e4 N/m, B = 2 N·s/m): K h < 2 (b + B) puts the limit at h = 0.40 ms.
  EXPECT_LT(run_held_spring(1e4, 2.0, kDamping, 0.36e-3, 1, 2000).final_peak, 0.001);
  EXPECT_GT(run_held_spring(1e4, 2.0, kDamping, 0.44e-3, 1, 2000).final_peak, 0.001);
}

}  // namespace
}  // namespace haptic::engine
