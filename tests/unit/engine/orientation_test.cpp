// Orientation: the rotation vector maps, the handle's rigid-body rotation, the orientation spring
// (its four laws) and detent, their potentials, their stability boundary against the sampled
// analysis of a wall (the same mathematics about one axis) and their cost (no allocation).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "engine/core/rotation.hpp"
#include "engine/device/rigid_body_rotation.hpp"
#include "engine/scene/orientation_fields.hpp"
#include "support/allocation_counter.hpp"

namespace haptic::engine {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = std::numbers::pi;

Vec3 unit(const Vec3& v) { return (1.0 / norm(v)) * v; }

// ---- rotation vectors ------------------------------------------------------------------------

TEST(Rotation, VectorMapsAreInverseAndTakeTheShortWay) {
  for (const Vec3& r : {Vec3{0, 0, 0}, Vec3{1e-9, 0, 0}, Vec3{0.3, -0.2, 0.1}, Vec3{0, 2.5, 0},
                        Vec3{-1.0, 1.0, 1.5}}) {
    const Vec3 back = rotation_vector(rotation_from_vector(r));
    EXPECT_NEAR(norm(back - r), 0.0, 1e-12) << r.x << " " << r.y << " " << r.z;
  }
  // q and −q are one rotation: the same vector.
  const Quat q = rotation_from_vector({0.2, 0.4, -0.1});
  const Vec3 a = rotation_vector(q);
  const Vec3 b = rotation_vector(Quat{-q.w, -q.x, -q.y, -q.z});
  EXPECT_NEAR(norm(a - b), 0.0, 1e-15);
  // A rotation by 4 rad about z is −(2π − 4) rad about z.
  const Vec3 wrapped = rotation_vector(quat_from_axis_angle({0, 0, 1}, 4.0));
  EXPECT_NEAR(wrapped.z, 4.0 - 2.0 * kPi, 1e-12);
}

TEST(Rotation, ErrorIsTheRotationFromTargetToToolInW) {
  const Quat target = quat_from_axis_angle({1, 0, 0}, 0.7);
  const Quat tool = quat_from_axis_angle({0, 0, 1}, 0.25) * target;  // 0.25 rad about z, in W
  const Vec3 theta = orientation_error_W(tool, target);
  EXPECT_NEAR(theta.x, 0.0, 1e-14);
  EXPECT_NEAR(theta.y, 0.0, 1e-14);
  EXPECT_NEAR(theta.z, 0.25, 1e-14);
}

// ---- the handle's rotation -------------------------------------------------------------------

TEST(RigidBodyRotation, AboutOneAxisItIsTheExactMassDamperStep) {
  // I ω̇ = τ − b ω with τ held: ω(t) = τ/b + (ω0 − τ/b) e^{−bt/I}, φ(t) = ∫ω.
  const RotationParams params{2e-4, 1e-3, 1};
  RigidBodyRotation body(params, RotationState{{}, {0, 0, 1.0}});
  const double tau = 0.01;
  const double dt = 1e-3;
  for (int k = 0; k < 500; ++k) body.step({0, 0, tau}, dt, [](const Quat&, const Vec3&) { return Vec3{}; });
  const double t = 500 * dt;
  const double a = params.damping / params.inertia;
  const double w_inf = tau / params.damping;
  const double w_exact = w_inf + (1.0 - w_inf) * std::exp(-a * t);
  const double angle_exact = w_inf * t + (1.0 - w_inf) * (1.0 - std::exp(-a * t)) / a;
  EXPECT_NEAR(body.state().w_WT.z, w_exact, 1e-10 * std::abs(w_exact));
  const Vec3 turned = rotation_vector(body.state().R_WT);
  // The angle wraps into [−π, π]: compare on the circle.
  const double difference = std::remainder(turned.z - angle_exact, 2.0 * kPi);
  EXPECT_NEAR(difference, 0.0, 1e-9);
  EXPECT_NEAR(norm(body.state().R_WT), 1.0, 1e-14);
}

TEST(RigidBodyRotation, TiltedTorqueConvergesAtSecondOrderInTheSubstep) {
  // A torque across the spin turns ω's direction within a tick; the sub-steps compose rotations,
  // whose commutator error falls as h².
  const auto run = [](std::uint32_t substeps) {
    RigidBodyRotation body(RotationParams{1e-4, 0.0, substeps}, RotationState{{}, {20.0, 0, 0}});
    for (int k = 0; k < 100; ++k) {
      body.step({0, 0.05, 0}, 1e-3, [](const Quat&, const Vec3&) { return Vec3{}; });
    }
    return body.state().R_WT;
  };
  const Quat reference = run(4096);
  const auto error = [&](std::uint32_t n) { return norm(orientation_error_W(run(n), reference)); };
  const double e1 = error(4), e2 = error(8), e3 = error(16);
  EXPECT_GT(e1 / e2, 3.5);
  EXPECT_LT(e1 / e2, 4.5);
  EXPECT_GT(e2 / e3, 3.5);
  EXPECT_LT(e2 / e3, 4.5);
}

TEST(RigidBodyRotation, ParametersAreCheckedByName) {
  EXPECT_EQ(validate_rotation(RotationParams{}), "");
  EXPECT_EQ(validate_rotation(RotationParams{0.0, 1e-3, 10}), "inertia: must be finite and > 0, got 0");
  EXPECT_EQ(validate_rotation(RotationParams{1e-4, -1.0, 10}), "damping: must be finite and >= 0, got -1");
  EXPECT_EQ(validate_rotation(RotationParams{1e-4, 0.0, 0}), "substeps: must be 1 to 1000, got 0");
}

// ---- the orientation spring ------------------------------------------------------------------

/// −dU/dε along a left perturbation exp(ε e_i) R, by central differences: the conservative torque.
template <class Potential>
Vec3 minus_gradient(const Potential& U, const Quat& R) {
  const double h = 1e-6;
  const Vec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  double g[3];
  for (int i = 0; i < 3; ++i) {
    g[i] = -(U(rotation_from_vector(h * axes[i]) * R) - U(rotation_from_vector(-h * axes[i]) * R)) / (2 * h);
  }
  return {g[0], g[1], g[2]};
}

TEST(OrientationSpring, TorqueIsMinusTheGradientOfItsPotentialAtEveryAngle) {
  OrientationSpringSpec spec;
  spec.R_WG = quat_from_axis_angle({0, 1, 1}, 0.4);
  spec.stiffness = 0.5;
  const auto U = [&](const Quat& R) {
    OrientationSpringState state;
    return state.update(spec, R, {}, 1e-3).U;
  };
  for (const Vec3& r : {Vec3{0.1, 0, 0}, Vec3{0.4, -1.0, 0.3}, Vec3{0, 0, 2.9}, Vec3{-2.0, 1.2, 0.5}}) {
    const Quat R = rotation_from_vector(r) * spec.R_WG;
    OrientationSpringState state;
    const OrientationSample sample = state.update(spec, R, {}, 1e-3);
    const Vec3 expected = minus_gradient(U, R);
    EXPECT_NEAR(norm(sample.tau_T_W - expected), 0.0, 1e-6 * (1.0 + norm(expected)))
        << "at |θ| = " << norm(r);
    EXPECT_NEAR(sample.U, 0.5 * spec.stiffness * dot(r, r), 1e-12);
  }
}

TEST(OrientationSpring, VelocityLawDampsTheMeasuredRateAndClips) {
  OrientationSpringSpec spec;
  spec.stiffness = 2.0;
  spec.damping = 0.1;
  OrientationSpringState state;
  const OrientationSample sample =
      state.update(spec, quat_from_axis_angle({1, 0, 0}, 0.1), {0, 0.5, 0}, 1e-3);
  EXPECT_NEAR(sample.tau_T_W.x, -0.2, 1e-12);
  EXPECT_NEAR(sample.tau_T_W.y, -0.05, 1e-12);
  spec.max_torque = 0.1;
  const OrientationSample clipped = state.update(spec, quat_from_axis_angle({1, 0, 0}, 0.1), {}, 1e-3);
  EXPECT_NEAR(norm(clipped.tau_T_W), 0.1, 1e-12);
  // Beyond the clip the potential grows linearly: F_max |θ| − F_max²/2k.
  EXPECT_NEAR(clipped.U, 0.1 * 0.1 - 0.01 / 4.0, 1e-12);
}

TEST(OrientationSpring, DiscreteLawsAreTheImpedanceFilterPerAxis) {
  const double T = 1e-3;
  for (const ContactLaw law : {ContactLaw::kBackwardDifference, ContactLaw::kExactZoh}) {
    OrientationSpringSpec spec;
    spec.stiffness = 1.5;
    spec.damping = 0.02;
    spec.law = law;
    OrientationSpringState state;
    state.set_weights(orientation_spring_weights(spec, T));
    ImpedanceFilter reference(ImpedanceParams{1.5, 0.02, 0.0}, discretization_of(law), T);
    // Turning about y at 2 rad/s from 0.05 rad: θ_y(k) = 0.05 + 2 k T; the filter starts from
    // θ(k−1) = θ(0) − T ω, so its first difference is the measured rate.
    const double w = 2.0;
    reference.reset(-(0.05 - T * w), -w);
    for (int k = 0; k < 50; ++k) {
      const double angle = 0.05 + w * k * T;
      const OrientationSample sample = state.update(spec, quat_from_axis_angle({0, 1, 0}, angle), {0, w, 0}, T);
      const double f = reference.update(-angle);
      EXPECT_NEAR(sample.tau_T_W.y, f, 1e-12) << "tick " << k;
      EXPECT_NEAR(sample.tau_T_W.x, 0.0, 1e-12);
    }
  }
}

TEST(OrientationSpring, ThePassageThroughPiRestartsTheFiltersWithoutASpike) {
  // The error's branch flips at π: θ jumps from +π−ε to −π+ε. Without the restart the backward
  // difference would see a rate of 2π/T.
  OrientationSpringSpec spec;
  spec.stiffness = 0.01;
  spec.damping = 0.001;
  spec.law = ContactLaw::kBackwardDifference;
  const double T = 1e-3;
  OrientationSpringState state;
  state.set_weights(orientation_spring_weights(spec, T));
  const double w = 1.0;
  double largest = 0.0;
  for (int k = -20; k <= 20; ++k) {
    const double angle = kPi + w * k * T;
    const OrientationSample sample = state.update(spec, quat_from_axis_angle({0, 0, 1}, angle), {0, 0, w}, T);
    largest = std::max(largest, norm(sample.tau_T_W));
  }
  EXPECT_LT(largest, spec.stiffness * kPi + spec.damping * w + 1e-9);
}

TEST(OrientationSpring, ParametersAreCheckedByName) {
  OrientationSpringSpec spec;
  spec.stiffness = 1.0;
  EXPECT_EQ(validate_orientation_spring(spec, 1e-3), "");
  spec.R_WG = Quat{2, 0, 0, 0};
  EXPECT_EQ(validate_orientation_spring(spec, 1e-3),
            "R_WG: norm must be 1 (a finite unit quaternion), got 2");
  spec.R_WG = Quat{};
  spec.damping = kNaN;
  EXPECT_EQ(validate_orientation_spring(spec, 1e-3), "damping: must be finite and >= 0, got nan");
  spec.damping = 0.0;
  spec.max_torque = -1.0;
  EXPECT_EQ(validate_orientation_spring(spec, 1e-3),
            "max_torque: must be finite and >= 0 (0: no clip), got -1");
}

// ---- the orientation detent ------------------------------------------------------------------

TEST(OrientationDetent, TorqueIsMinusTheGradientAndVanishesBeyondTheRim) {
  OrientationDetentSpec spec;
  spec.R_WG = quat_from_axis_angle({1, 0, 0}, -0.3);
  spec.depth = 0.01;
  spec.radius = 0.2;
  spec.rim_height = 0.004;
  spec.rim_width = 0.1;
  ASSERT_EQ(validate_orientation_detent(spec), "");
  const auto U = [&](const Quat& R) { return evaluate_orientation_detent(spec, R, {}).U; };
  for (const double angle : {0.05, 0.1, 0.19, 0.25, 0.29}) {
    const Quat R = rotation_from_vector(angle * unit({1, 2, -1})) * spec.R_WG;
    const OrientationSample sample = evaluate_orientation_detent(spec, R, {});
    const Vec3 expected = minus_gradient(U, R);
    EXPECT_NEAR(norm(sample.tau_T_W - expected), 0.0, 1e-7) << "at " << angle << " rad";
  }
  EXPECT_NEAR(U(spec.R_WG), -spec.depth, 1e-15);
  const Quat outside = rotation_from_vector({0, 0, 0.31}) * spec.R_WG;
  EXPECT_EQ(evaluate_orientation_detent(spec, outside, {0, 0, 5}).tau_T_W, Vec3{});
  // Near the target a spring of 6 (D + H) / R².
  const OrientationSample near =
      evaluate_orientation_detent(spec, rotation_from_vector({0, 1e-4, 0}) * spec.R_WG, {});
  EXPECT_NEAR(near.tau_T_W.y / -1e-4, 6.0 * (spec.depth + spec.rim_height) / (0.2 * 0.2), 1e-2);
}

TEST(OrientationDetent, ParametersAreCheckedByName) {
  OrientationDetentSpec spec;
  spec.depth = 0.01;
  spec.radius = 2.0;
  spec.rim_width = 1.5;
  EXPECT_EQ(validate_orientation_detent(spec), "rim_width: must keep radius + rim_width <= pi rad, got 3.5");
  spec.rim_width = 0.0;
  EXPECT_EQ(validate_orientation_detent(spec), "rim_width: must be finite and > 0, got 0");
  spec.rim_width = 0.5;
  spec.depth = 0.0;
  EXPECT_EQ(validate_orientation_detent(spec), "depth: must be finite and > 0, got 0");
}

// ---- stability about one axis ----------------------------------------------------------------

/// Runs the handle (inertia I, damping b) in closed loop with a spring of stiffness k (law, no
/// spring damping) from 0.01 rad about z for `ticks` ticks at period T; returns the last 200 ticks'
/// largest |θ| over the first 200 ticks' (> 1: the oscillation grows).
double growth(double k, ContactLaw law, const RotationParams& handle, double T, int ticks) {
  OrientationSpringSpec spec;
  spec.stiffness = k;
  spec.law = law;
  OrientationSpringState state;
  state.set_weights(orientation_spring_weights(spec, T));
  RigidBodyRotation body(handle, RotationState{quat_from_axis_angle({0, 0, 1}, 0.01), {}});
  double early = 0.0, late = 0.0;
  for (int tick = 0; tick < ticks; ++tick) {
    const OrientationSample sample = state.update(spec, body.state().R_WT, body.state().w_WT, T);
    body.step(sample.tau_T_W, T, [](const Quat&, const Vec3&) { return Vec3{}; });
    const double angle = std::abs(rotation_vector(body.state().R_WT).z);
    if (tick < 200) early = std::max(early, angle);
    if (tick >= ticks - 200) late = std::max(late, angle);
  }
  return late / early;
}

TEST(OrientationSpring, StabilityBoundaryAboutOneAxisIsTheSampledWallMargin) {
  // About one axis the handle is I θ̈ + b θ̇ = τ, a 1-DOF mass-damper: the wall's closed loop with
  // m → I and K → k (impedance.hpp, wall_characteristic_polynomial). The spring is stable below
  // K' and unstable above it, as the Jury test of that polynomial says.
  const RotationParams handle{1e-4, 5e-4, 10};
  const double T = 1e-3;
  for (const ContactLaw law : {ContactLaw::kBackwardDifference, ContactLaw::kExactZoh}) {
    const SampledWallMargin margin = sampled_wall_margin(
        ImpedanceParams{1.0, 0.0, 0.0}, discretization_of(law), MassDamperDevice{handle.inertia, handle.damping}, T);
    const double k_max = margin.max_stable_stiffness;
    ASSERT_TRUE(std::isfinite(k_max) && k_max > 0.0);
    EXPECT_LT(growth(0.9 * k_max, law, handle, T, 20000), 1.0) << "0.9 K' decays";
    EXPECT_GT(growth(1.1 * k_max, law, handle, T, 20000), 1.0) << "1.1 K' grows";
  }
}

TEST(OrientationFields, UpdateAllocatesNothing) {
  OrientationSpringSpec spring;
  spring.stiffness = 0.3;
  spring.damping = 0.001;
  spring.law = ContactLaw::kExactZoh;
  OrientationSpringState state;
  state.set_weights(orientation_spring_weights(spring, 1e-3));
  OrientationDetentSpec detent{{}, 0.01, 0.3, 0.0, 0.1, 0.0};
  double sink = 0.0;
  haptic::test::reset_allocations();
  {
    haptic::test::CountAllocations counting;
    for (int k = 0; k < 2000; ++k) {
      const Quat R = rotation_from_vector({0.3 * std::sin(k * 1e-3), 0.2, -0.1});
      sink += state.update(spring, R, {0.1, 0, 0}, 1e-3).tau_T_W.x;
      sink += evaluate_orientation_detent(detent, R, {0.1, 0, 0}).tau_T_W.y;
    }
  }
  EXPECT_EQ(haptic::test::allocations(), 0u);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace haptic::engine
