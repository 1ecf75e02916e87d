// The 6-DOF point mass in lockstep through the loop's own tick: an orientation spring's torque in
// the sample and on the handle, its energy bookkeeping, its stability boundary against the sampled
// analysis, and no orientation work where the scene or the device does not need it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "engine/core/rotation.hpp"
#include "haptic/wire/datagram.hpp"
#include "runtime/cartesian_model.hpp"
#include "runtime/flush_denormals.hpp"
#include "runtime/simulated_point_mass_device.hpp"
#include "runtime/tick_runner.hpp"
#include "support/allocation_counter.hpp"

namespace haptic::runtime {
namespace {

constexpr double kPeriod = 0.001;
// The handle of config/six_dof.json and the simulated_point_mass.rotation defaults.
constexpr double kInertia = 1e-4;  // kg·m²
constexpr double kDamping = 5e-4;  // N·m·s/rad

engine::CompiledScene spring_scene(double stiffness, double damping, engine::ContactLaw law,
                                   std::uint64_t generation = 1) {
  engine::SceneDescription description;
  engine::OrientationSpringSpec spring;
  spring.stiffness = stiffness;
  spring.damping = damping;
  spring.law = law;
  description.fields.push_back(engine::FieldEntry{{0, 7, engine::kNeverTick, {}}, engine::FieldSpec{spring}});
  return engine::compile_scene(description, 50, generation, kPeriod);
}

std::optional<SimulatedRotation> handle(double angle_z) {
  SimulatedRotation rotation;
  rotation.params = engine::RotationParams{kInertia, kDamping, 10};
  rotation.initial.R_WT = engine::quat_from_axis_angle({0, 0, 1}, angle_z);
  rotation.max_torque = 0.2;
  return rotation;
}

/// The 6-DOF device (or the 3-DOF one, without a handle), a scene, a ring and a runner, wired as
/// the server wires them.
struct Rig {
  Rig(engine::CompiledScene compiled, std::optional<SimulatedRotation> rotation)
      : device(engine::PointMassParams{}, engine::PointMassState{{0.0, 0.0, 0.02}, {}}, 20.0, rotation),
        owned(std::make_unique<const engine::CompiledScene>(std::move(compiled))),
        scene(owned.get()),
        scenes(std::move(owned)),
        runner(device, model, scenes, samples, counters, TickConfig{kPeriod, {}, 50, {}}) {}

  TickSample run_one() {
    ++tick;
    runner.run(tick, static_cast<std::int64_t>(tick - 1) * 1'000'000);
    TickSample sample;
    samples.read(tick, sample);
    return sample;
  }
  double angle_z() const { return engine::rotation_vector(device.rotation()->state().R_WT).z; }

  SimulatedPointMassDevice device;
  CartesianModel model;
  std::unique_ptr<const engine::CompiledScene> owned;  // until the exchange takes it
  const engine::CompiledScene* scene;                  // the one scene of the run
  SceneExchange scenes;
  SampleRing samples;
  LoopCounters counters;
  TickRunner runner;
  std::uint64_t tick = 0;
};

TEST(SixDofTick, TheSpringsTorqueIsInTheSampleAndTurnsTheHandleToItsTarget) {
  const double k = 0.05;  // N·m/rad
  Rig rig(spring_scene(k, 0.0, engine::ContactLaw::kVelocity), handle(0.2));
  const TickSample first = rig.run_one();
  EXPECT_TRUE(first.has_orientation);
  // τ = −k θ, θ = 0.2 rad about z (the guard lets 0.01 N·m through at once: under its rate).
  EXPECT_NEAR(first.tau_T_W.z, -k * 0.2, 1e-12);
  EXPECT_NEAR(first.tau_T_W.x, 0.0, 1e-15);
  EXPECT_EQ(first.F_T_W, engine::Vec3{});  // no force field: the position is left alone
  // Under-damped by the handle's own b (ζ = b / 2√(kI) ≈ 0.11): it rings down onto the target.
  for (int i = 0; i < 5000; ++i) rig.run_one();
  EXPECT_LT(std::abs(rig.angle_z()), 2e-4);
}

TEST(SixDofTick, AStiffSpringFarFromItsTargetIsHeldToTheDevicesMaxTorqueAndFlagged) {
  // 10 N·m/rad at 0.5 rad asks for 5 N·m; the handle takes at most max_torque = 0.2 N·m. The
  // torque guard is built from max_torque (not the 20 N max_force, which would let 5 N·m by).
  const double k = 10.0;
  Rig rig(spring_scene(k, 0.0, engine::ContactLaw::kVelocity), handle(0.5));
  bool saturated = false;
  double largest = 0.0;
  for (int i = 0; i < 20; ++i) {
    const TickSample sample = rig.run_one();
    const double magnitude = std::sqrt(sample.tau_T_W.x * sample.tau_T_W.x +
                                       sample.tau_T_W.y * sample.tau_T_W.y +
                                       sample.tau_T_W.z * sample.tau_T_W.z);
    largest = std::max(largest, magnitude);
    EXPECT_LE(magnitude, 0.2 + 1e-12) << "tick " << i;
    saturated = saturated || (sample.flags & wire::kFlagForceSaturated) != 0;
  }
  EXPECT_NEAR(largest, 0.2, 1e-12);  // it reaches the limit (past the guard's rate limit)
  EXPECT_TRUE(saturated);
}

TEST(SixDofTick, TheDeviceRefusesANonFiniteTorqueAndItsOrientationStaysFinite) {
  // The second layer behind the tick's torque guard: the simulated handle itself never takes a
  // NaN torque (it turns the handle by none that tick and reports an error).
  SimulatedPointMassDevice device(engine::PointMassParams{}, engine::PointMassState{{0.0, 0.0, 0.02}, {}},
                                  20.0, handle(0.3));
  DeviceReading reading;
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  DeviceCommand command;
  command.tau_W = {std::nan(""), 0.0, 0.0};
  EXPECT_EQ(device.write(command, kPeriod), DeviceStatus::kError);
  const engine::Quat R = device.rotation()->state().R_WT;
  EXPECT_TRUE(std::isfinite(R.w) && std::isfinite(R.x) && std::isfinite(R.y) && std::isfinite(R.z));
  EXPECT_NEAR(engine::rotation_vector(R).z, 0.3, 1e-9);  // not turned by it
  const engine::Vec3 w = device.rotation()->state().w_WT;
  EXPECT_TRUE(std::isfinite(w.x) && std::isfinite(w.y) && std::isfinite(w.z));
  // A finite torque afterwards is taken again.
  command.tau_W = {0.0, 0.0, 0.01};
  EXPECT_EQ(device.write(command, kPeriod), DeviceStatus::kOk);
}

TEST(SixDofTick, TheSpringsEnergyIsBookedAsTheWorkOfItsTorque) {
  // With b = 0 the spring is conservative: the work its torque does on the handle, as the meter
  // books it (the trapezoidal ∫τ·ω between ticks), is U(start) − U(now); what the spring gave
  // went into the handle's kinetic energy and its damping.
  const double k = 0.05;
  const double theta0 = 0.2;
  Rig rig(spring_scene(k, 0.0, engine::ContactLaw::kVelocity), handle(theta0));
  for (int i = 0; i < 3000; ++i) rig.run_one();
  const auto totals = engine::energy_totals(*rig.scene);
  ASSERT_EQ(totals.size(), 1u);
  const double net = totals[0].given - totals[0].absorbed;
  const double theta = rig.angle_z();
  const double U_start = 0.5 * k * theta0 * theta0;
  const double U_now = 0.5 * k * theta * theta;
  std::printf("orientation spring: given %.6g J, absorbed %.6g J, U(start) - U(now) %.6g J\n",
              totals[0].given, totals[0].absorbed, U_start - U_now);
  EXPECT_NEAR(net, U_start - U_now, 0.01 * U_start);
  EXPECT_GT(totals[0].absorbed, 0.0);  // the ringing handle gave energy back on every swing in
  // The plant's own account: what the spring's work became, kinetic energy plus the handle's
  // damping's dissipation, is less than the spring gave only by the meter's sampling error.
  const double kinetic = 0.5 * kInertia * std::pow(rig.device.rotation()->state().w_WT.z, 2);
  EXPECT_LT(kinetic, net);
}

/// The largest |θ| over the last 200 ticks of `ticks` over that of the first 200: above 1 the
/// closed loop of the handle and the spring rings up.
double growth(double k, double b, engine::ContactLaw law, int ticks) {
  Rig rig(spring_scene(k, b, law), handle(0.01));
  double early = 0.0, late = 0.0;
  for (int tick = 0; tick < ticks; ++tick) {
    rig.run_one();
    const double angle = std::abs(rig.angle_z());
    if (tick < 200) early = std::max(early, angle);
    if (tick >= ticks - 200) late = std::max(late, angle);
  }
  return late / early;
}

TEST(SixDofTick, StabilityBoundaryOfTheSpringIsTheAnalyticOne) {
  // About one axis the handle is I θ̈ + b θ̇ = τ; the sampled analysis of a wall on a mass-damper
  // (impedance.hpp, wall_characteristic_polynomial with m → I) gives the largest stable k. The
  // whole loop — device, guard, scene stage — agrees on both sides of it.
  // A spring's own damper b_s moves the boundary (the exact ZOH form equals the backward
  // difference at b_s = 0, 000 eq. 8.12's limit).
  const struct {
    engine::ContactLaw law;
    double spring_damping;  // N·m·s/rad
  } cases[] = {{engine::ContactLaw::kBackwardDifference, 0.0},
               {engine::ContactLaw::kBackwardDifference, 2e-4},
               {engine::ContactLaw::kExactZoh, 2e-4}};
  for (const auto& c : cases) {
    const engine::SampledWallMargin margin = engine::sampled_wall_margin(
        engine::ImpedanceParams{1.0, c.spring_damping, 0.0}, engine::discretization_of(c.law),
        engine::MassDamperDevice{kInertia, kDamping}, kPeriod);
    const double k_max = margin.max_stable_stiffness;
    ASSERT_TRUE(std::isfinite(k_max) && k_max > 0.0);
    const double below = growth(0.9 * k_max, c.spring_damping, c.law, 20000);
    const double above = growth(1.1 * k_max, c.spring_damping, c.law, 20000);
    std::printf("law %d, b_s %g: K' = %.6g N*m/rad (Colgate's passive bound 2(b - b_s)/T: %.6g); "
                "growth at 0.9 K' %.3g, at 1.1 K' %.3g\n",
                static_cast<int>(c.law), c.spring_damping, k_max,
                2.0 * (kDamping - c.spring_damping) / kPeriod, below, above);
    EXPECT_LT(below, 1.0);
    EXPECT_GT(above, 1.0);
  }
}

TEST(SixDofTick, NoOrientationWorkWhereTheSceneOrTheDeviceNeedsNone) {
  // A scene without orientation fields has no orientation stage; the 6-DOF device gets no torque.
  engine::SceneDescription empty;
  const engine::CompiledScene scene = engine::compile_scene(empty, 50, 1, kPeriod);
  EXPECT_EQ(scene.stages & engine::kStageOrientation, 0u);
  Rig six(engine::compile_scene(empty, 50, 1, kPeriod), handle(0.2));
  EXPECT_EQ(six.run_one().tau_T_W, engine::Vec3{});
  // A 3-DOF device with an orientation spring in the scene: the stage is there, but this port
  // neither computes nor commands a torque (its spring's filters never start).
  Rig three(spring_scene(0.05, 0.0, engine::ContactLaw::kBackwardDifference), std::nullopt);
  EXPECT_NE(three.scene->stages & engine::kStageOrientation, 0u);
  for (int i = 0; i < 10; ++i) EXPECT_EQ(three.run_one().tau_T_W, engine::Vec3{});
  EXPECT_FALSE(three.scene->state->orientations[0].spring.started);
}

TEST(SixDofTick, ATickWithOrientationFieldsAllocatesNothing) {
  Rig rig(spring_scene(0.05, 0.001, engine::ContactLaw::kExactZoh), handle(0.2));
  rig.run_one();  // adopts the scene
  haptic::test::reset_allocations();
  {
    haptic::test::CountAllocations counting;
    for (int i = 0; i < 1000; ++i) rig.run_one();
  }
  EXPECT_EQ(haptic::test::allocations(), 0u);
}

}  // namespace
}  // namespace haptic::runtime

namespace haptic::runtime {
namespace {

double volatile_product(double a, double b) {
  volatile double x = a;
  volatile double y = b;
  return x * y;
}

TEST(FlushDenormals, DenormalsAreZeroForTheTickAndTheModeIsRestoredAfter) {
  const double tiny = 1e-310;  // below 2.2e-308: a denormal
  ASSERT_GT(volatile_product(tiny, 1.0), 0.0);
  {
    const FlushDenormals scope;
#if defined(__x86_64__) || defined(__i386__) || defined(__aarch64__)
    EXPECT_EQ(volatile_product(tiny, 1.0), 0.0);
    EXPECT_EQ(volatile_product(1e-300, 1e-10), 0.0);  // a result in the denormal range
#endif
  }
  EXPECT_GT(volatile_product(tiny, 1.0), 0.0);  // the caller's mode again
}

}  // namespace
}  // namespace haptic::runtime
