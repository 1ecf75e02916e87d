// The passivity observer and controller (Hannaford & Ryu 2002): single-tick arithmetic, and a
// stiff, sampling-active wall on document 001's light device made passive, while a passive wall
// is left alone.
#include <gtest/gtest.h>

#include <limits>

#include <algorithm>
#include <cmath>

#include "engine/device/point_mass_plant.hpp"
#include "engine/safety/passivity.hpp"
#include "engine/scene/impedance.hpp"
#include "support/allocation_counter.hpp"

namespace haptic::engine {
namespace {

constexpr double kT = 1e-3;

TEST(Passivity, ObserverSumsPowerIntoTheEnvironment) {
  PassivityObserver sampled(kT, PassivityObserverMode::kSampledPower);
  // The tool pushes into a wall (v −z) that pushes back (F +z): the wall absorbs.
  EXPECT_DOUBLE_EQ(sampled.observe({0, 0, 2.0}, {0, 0, -0.1}, {}), 2e-4);
  // The wall pushes the tool out (v +z): it gives energy back.
  EXPECT_DOUBLE_EQ(sampled.observe({0, 0, 3.0}, {0, 0, 0.1}, {}), 2e-4 - 3e-4);
  sampled.reset();
  EXPECT_EQ(sampled.energy(), 0.0);
  // The held force's work is booked when its period completes: 2 N held while the tool moved
  // 0.15 mm into the wall, then 3 N while it moved 0.05 mm out.
  PassivityObserver held(kT, PassivityObserverMode::kHeldForceWork);
  EXPECT_EQ(held.observe({0, 0, 2.0}, {0, 0, -0.1}, {0, 0, 0.0}), 0.0);
  EXPECT_DOUBLE_EQ(held.observe({0, 0, 3.0}, {0, 0, 0.1}, {0, 0, -1.5e-4}), 3e-4);
  EXPECT_DOUBLE_EQ(held.observe({}, {}, {0, 0, -1e-4}), 3e-4 - 1.5e-4);
  held.reset();
  EXPECT_EQ(held.observe({0, 0, 1.0}, {}, {0, 0, 5.0}), 0.0);  // no period completed yet
}

TEST(Passivity, ControllerAddsExactlyTheDampingThatCancelsTheDeficit) {
  PassivityControllerParams params{kT, 100.0, 1e-4, PassivityObserverMode::kSampledPower};
  PassivityController pc(params);
  // Absorbing tick: no action.
  PassivityStep step = pc.apply({0, 0, 1.0}, {0, 0, -0.2}, {});
  EXPECT_EQ(step.alpha, 0.0);
  EXPECT_DOUBLE_EQ(step.energy, 2e-4);
  // Returning 1e-3 J (T F·v): E_obs = 2e-4 − 1e-3 = −8e-4, so α = 8e-4 / (T |v|²), along v.
  const Vec3 v{0.3, 0.0, 0.4};  // |v| = 0.5
  const Vec3 F{0, 0, 2.5};
  step = pc.apply(F, v, {});
  const double E_observed = 2e-4 - kT * dot(F, v);
  ASSERT_LT(E_observed, 0.0);
  EXPECT_NEAR(step.alpha, -E_observed / (kT * 0.25), 1e-9);
  EXPECT_FALSE(step.limited);
  // The added force is a damper along v, and E is back at zero.
  const Vec3 added = step.F_T_W - F;
  EXPECT_NEAR(norm(cross(added, v)), 0.0, 1e-12);
  EXPECT_LT(dot(added, v), 0.0);
  EXPECT_NEAR(step.energy, 0.0, 1e-15);
  EXPECT_NEAR(pc.dissipated(), -E_observed, 1e-15);
}

TEST(Passivity, ANonFiniteRequestDoesNotSwitchTheControllerOff) {
  // A field whose force overflowed once (the guard faults it to zero) must not leave the port's
  // controller holding a NaN energy, which no later deficit could ever exceed.
  PassivityControllerParams params{kT, 100.0, 1e-4, PassivityObserverMode::kHeldForceWork};
  PassivityController fresh(params), hit(params);
  const double inf = std::numeric_limits<double>::infinity();
  const PassivityStep faulted = hit.apply({0, 0, inf}, {0, 0, 0.1}, {0, 0, 0.01});
  EXPECT_EQ(faulted.alpha, 0.0);
  EXPECT_EQ(hit.energy(), 0.0);
  // From here both see the same active contact (the scene returning energy, F·v > 0): both act,
  // identically.
  for (int k = 0; k < 20; ++k) {
    const Vec3 p{0, 0, 0.01 + 1e-4 * k}, v{0, 0, 0.1}, F{0, 0, 2.0};
    const PassivityStep a = fresh.apply(F, v, p);
    const PassivityStep b = hit.apply(F, v, p);
    EXPECT_EQ(a.alpha, b.alpha) << k;
    EXPECT_EQ(a.F_T_W, b.F_T_W) << k;
  }
  EXPECT_GT(hit.dissipated(), 0.0);
  EXPECT_EQ(hit.dissipated(), fresh.dissipated());
}

TEST(Passivity, ANonFiniteRequestAfterContactForgetsTheStoredEnergy) {
  // 1.8 mJ absorbed by earlier contact, then one non-finite request: the energy the port held
  // before the fault must not carry over, or it pays for the active contact that follows and the
  // controller lets the scene generate energy undamped for tick after tick.
  PassivityControllerParams params{kT, 100.0, 1e-4, PassivityObserverMode::kHeldForceWork};
  PassivityController fresh(params), hit(params);
  // The tool presses into a wall at 0.1 m/s against 2 N: 0.2 mJ absorbed per completed period.
  Vec3 p{0, 0, 0.01};
  for (int k = 0; k < 10; ++k) {
    const PassivityStep step = hit.apply({0, 0, 2.0}, {0, 0, -0.1}, p);
    ASSERT_EQ(step.alpha, 0.0) << k;  // absorbing: nothing to do
    p.z -= 1e-4;
  }
  ASSERT_NEAR(hit.energy(), 1.8e-3, 1e-12);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const PassivityStep faulted = hit.apply({0, 0, nan}, {0, 0, 0.0}, p);
  EXPECT_EQ(faulted.alpha, 0.0);
  EXPECT_EQ(hit.energy(), 0.0);
  EXPECT_EQ(hit.dissipated(), 0.0);
  // Then active contact (the wall pushes the tool out, F·v > 0): the controller damps from the
  // first tick on, exactly as one that never saw the earlier contact.
  for (int k = 0; k < 30; ++k) {
    const Vec3 v{0, 0, 0.1}, F{0, 0, 1.0};
    const PassivityStep a = fresh.apply(F, v, p);
    const PassivityStep b = hit.apply(F, v, p);
    EXPECT_GT(b.alpha, 0.0) << k;
    EXPECT_LT(b.F_T_W.z, F.z) << k;
    EXPECT_EQ(a.alpha, b.alpha) << k;
    EXPECT_EQ(a.F_T_W, b.F_T_W) << k;
    EXPECT_EQ(a.energy, b.energy) << k;
    p.z += 1e-4;
  }
  EXPECT_EQ(hit.dissipated(), fresh.dissipated());
}

TEST(Passivity, ControllerClampsAlphaAndIgnoresSlowMotion) {
  PassivityController pc({kT, 2.0, 1e-3, PassivityObserverMode::kSampledPower});
  // A deficit of 1e-3 J at |v| = 0.1 would need α = 100: cut at 2, E stays negative.
  PassivityStep step = pc.apply({0, 0, 10.0}, {0, 0, 0.1}, {});
  EXPECT_TRUE(step.limited);
  EXPECT_EQ(step.alpha, 2.0);
  EXPECT_NEAR(step.energy, -1e-3 + 2.0 * kT * 0.01, 1e-15);
  // Below v_min nothing happens, whatever the deficit.
  const double before = pc.energy();
  step = pc.apply({0, 0, 10.0}, {0, 0, 5e-4}, {});
  EXPECT_EQ(step.alpha, 0.0);
  EXPECT_EQ(step.F_T_W, (Vec3{0, 0, 10.0}));
  EXPECT_NEAR(step.energy, before - kT * 10.0 * 5e-4, 1e-15);
  // Zero velocity with v_min = 0: no division by zero.
  PassivityController zero({kT, 2.0, 0.0, PassivityObserverMode::kSampledPower});
  zero.apply({0, 0, 10.0}, {0, 0, 0.1}, {});
  step = zero.apply({0, 0, 10.0}, {}, {});
  EXPECT_EQ(step.alpha, 0.0);
  pc.reset();
  EXPECT_EQ(pc.energy(), 0.0);
  EXPECT_EQ(pc.dissipated(), 0.0);
}

TEST(Passivity, ParamsForADeviceAndValidation) {
  const PassivityControllerParams params = passivity_params_for_device(0.01, kT, 1e-4);
  EXPECT_DOUBLE_EQ(params.max_damping, 10.0);  // m / T
  EXPECT_EQ(params.velocity_threshold, 1e-4);
  EXPECT_EQ(validate_passivity(params), "");
  EXPECT_EQ(validate_passivity({0.0, 1.0, 0.0}), "period: must be finite and > 0, got 0");
  EXPECT_EQ(validate_passivity({kT, NAN, 0.0}), "max_damping: must be finite and >= 0, got nan");
  EXPECT_EQ(validate_passivity({kT, 1.0, -1.0}),
            "velocity_threshold: must be finite and >= 0, got -1");
}

struct WallRun {
  double min_energy = 0.0;           // lowest E(n) the observer saw. Unit: J.
  double max_alpha = 0.0;            // largest α applied. Unit: N·s/m.
  int acting_ticks = 0;
  double early_speed = 0.0;          // peak |v| over 0.1–0.3 s. Unit: m/s.
  double late_speed = 0.0;           // peak |v| over the last 0.2 s. Unit: m/s.
  double final_penetration = 0.0;    // Unit: m.
  double max_height = 0.0;           // highest rebound over the last 0.5 s. Unit: m.
};

/// Document 001's device (m = 0.01 kg, b = 0.022 N·s/m) pushed by a 0.5 N hand onto the wall
/// x < 0 (a one-sided spring-damper behind the backward difference), from 1 mm above at
/// 0.1 m/s, for 4 s at 1 kHz; with or without the passivity controller at the port.
WallRun run_wall(double K, double B, bool controlled,
                 PassivityObserverMode mode = PassivityObserverMode::kHeldForceWork) {
  PointMassParams params;
  params.substeps = 10;
  params.workspace_min = {-1.0, -1.0, -1.0};
  params.workspace_max = {1.0, 1.0, 1.0};
  PointMassPlant plant(params, {{0.001, 0, 0}, {-0.1, 0, 0}});
  ImpedanceFilter wall({K, B, 0.0}, ImpedanceDiscretization::kBackwardDifference, kT);
  PassivityControllerParams pc_params = passivity_params_for_device(params.mass, kT, 1e-4);
  pc_params.observer = mode;
  PassivityController pc(pc_params);
  const auto hand = [](const Vec3&, const Vec3&) { return Vec3{-0.5, 0, 0}; };
  WallRun run;
  bool in_contact = false;
  double previous_d = -0.001;
  const int ticks = 4000;
  for (int k = 0; k < ticks; ++k) {
    const Vec3 p = plant.state().p_WT, v = plant.state().v_WT;
    const double d = -p.x;
    Vec3 F;
    if (d > 0.0) {
      if (!in_contact) wall.reset(previous_d);
      in_contact = true;
      F.x = std::max(0.0, wall.update(d));  // the wall only pushes
    } else {
      in_contact = false;
    }
    previous_d = d;
    if (controlled) {
      const PassivityStep step = pc.apply(F, v, p);
      F = step.F_T_W;
      run.min_energy = std::min(run.min_energy, step.energy);
      run.max_alpha = std::max(run.max_alpha, step.alpha);
      if (step.alpha > 0.0) ++run.acting_ticks;
    }
    plant.step(F, kT, hand);
    const double t = (k + 1) * kT;
    const double speed = norm(plant.state().v_WT);
    if (t > 0.1 && t <= 0.3) run.early_speed = std::max(run.early_speed, speed);
    if (k >= ticks - 200) run.late_speed = std::max(run.late_speed, speed);
    if (k >= ticks - 500) run.max_height = std::max(run.max_height, plant.state().p_WT.x);
  }
  run.final_penetration = -plant.state().p_WT.x;
  return run;
}

TEST(Passivity, ActiveStiffWallOnALightDeviceIsMadePassiveAndSettles) {
  // K = 20000 N/m at T = 1 ms needs b > KT/2 = 10 N·s/m (Madill eq. 2.6); the device has 0.022.
  const double K = 20000.0;
  ASSERT_GT(colgate_bound(K, 0.0, kT), 400.0 * 0.022);
  const WallRun free = run_wall(K, 0.0, false);
  // Uncontrolled, the wall generates energy: the tool keeps bouncing, higher than it started.
  EXPECT_GT(free.max_height, 0.001);
  EXPECT_GT(free.late_speed, 0.1);
  const WallRun controlled = run_wall(K, 0.0, true);
  EXPECT_GT(controlled.acting_ticks, 0);
  EXPECT_LE(controlled.max_alpha, 10.0);  // α_max = m/T
  // The observed energy never goes below −ε; ε = 1.5e-3 J is what one bounce can generate before
  // the clipped damper has taken it out (the hand's 0.5 N does 5e-4 J per millimetre).
  EXPECT_GE(controlled.min_energy, -1.5e-3);
  // And the motion decays onto the static balance d = 0.5 N / K.
  EXPECT_LT(controlled.late_speed, 0.01);
  EXPECT_LT(controlled.late_speed, 0.05 * controlled.early_speed);
  EXPECT_LT(controlled.max_height, 2e-4);
  EXPECT_NEAR(controlled.final_penetration, 0.5 / K, 1e-5);
}

TEST(Passivity, SampledPowerObserverMissesTheZohWorkOfAStiffWall) {
  // Hannaford & Ryu's sampled power T F(k)·v(k) over a contact of two or three samples
  // (ωT = 1.4) reads the active wall as passive nearly throughout: the controller acts on under
  // 1 % of the ticks, and the tool runs away.
  const WallRun run = run_wall(20000.0, 0.0, true, PassivityObserverMode::kSampledPower);
  EXPECT_GE(run.min_energy, -1e-12);
  EXPECT_LT(run.acting_ticks, 40) << run.acting_ticks;
  EXPECT_GT(run.late_speed, 0.1);
}

TEST(Passivity, PassiveWallNeverTriggersTheController) {
  // B > KT/2: the observed energy of the sampled spring-damper grows by about (B − KT/2) v² T a
  // tick (the sampled spring's deficit is K v² T²/2 a tick), so it never goes negative.
  for (const auto& [K, B] : {std::pair{1000.0, 1.0}, std::pair{2000.0, 2.0}, std::pair{200.0, 0.5}}) {
    const WallRun run = run_wall(K, B, true);
    EXPECT_EQ(run.acting_ticks, 0) << K << " " << B;
    EXPECT_EQ(run.max_alpha, 0.0);
    EXPECT_GE(run.min_energy, 0.0);
    EXPECT_LT(run.late_speed, 1e-3) << K << " " << B;  // and it settles by itself
  }
}

TEST(Passivity, ApplyAllocatesNothing) {
  PassivityController pc({kT, 10.0, 1e-4, PassivityObserverMode::kHeldForceWork});
  double sum = 0.0;
  haptic::test::reset_allocations();
  {
    haptic::test::CountAllocations counting;
    for (int k = 0; k < 1000; ++k) {
      const double s = std::sin(0.05 * k);
      sum += pc.apply({0, 0, 5.0 * s}, {0, 0, 0.1 * std::cos(0.05 * k)}, {0, 0, 0.002 * s}).F_T_W.z;
    }
  }
  EXPECT_EQ(haptic::test::allocations(), 0u);
  EXPECT_TRUE(std::isfinite(sum));
}

}  // namespace
}  // namespace haptic::engine
