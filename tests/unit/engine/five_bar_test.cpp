// Document 003's five-bar haptic device (Madill 1998): kinematics (eqs. 3.118, 3.120, 5.1–5.3),
// the balanced, decoupled dynamics (eq. 4.10, L2382), Table 5.4's friction identification,
// the D/A torque limit (L3237), the encoders (Table 5.2), the flexible link's frequencies
// (eqs. 5.10, 5.11) and the plant's optional flexible mode (eqs. 3.29–3.31).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "engine/device/five_bar.hpp"
#include "engine/device/flexible_link.hpp"

namespace haptic::engine {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

double wrap(double a) { return std::remainder(a, 2.0 * kPi); }

FiveBarParams frictionless() {
  FiveBarParams p;
  for (auto& f : p.friction) f = {0.0, 0.0, 1e-3};
  return p;
}

// ---------------------------------------------------------------------------------------------
// Kinematics.

TEST(FiveBarKinematics, HomePoseAndJacobianAtHome_Eq3_120) {
  const FiveBarParams p;
  const FiveBarJoints home = five_bar_home();
  EXPECT_DOUBLE_EQ(home[1], 90.0 * kDeg);
  EXPECT_DOUBLE_EQ(home[2], 180.0 * kDeg);
  const Vec3 tip = five_bar_tip_position(p, home);
  EXPECT_NEAR(tip.x, 0.60, 1e-15);  // l_f in front of the fulcrum
  EXPECT_NEAR(tip.y, 0.0, 1e-15);
  EXPECT_NEAR(tip.z, 0.30, 1e-15);  // l1 above it
  const FiveBarMatrix J = five_bar_jacobian(p, home);
  const double expected[3][3] = {{0.0, -0.3, 0.0}, {0.6, 0.0, 0.0}, {0.0, 0.0, 0.6}};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(J[r][c], expected[r][c], 1e-15) << r << "," << c;
  }
}

// Eq. 3.120 is the derivative of eq. 3.118's translation: compare with central differences.
TEST(FiveBarKinematics, JacobianMatchesCentralDifferences_Eq3_120) {
  const FiveBarParams p;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  double worst = 0.0;
  for (int n = 0; n < 500; ++n) {
    const FiveBarJoints q{angle(rng), angle(rng), angle(rng)};
    const FiveBarMatrix J = five_bar_jacobian(p, q);
    const double h = 1e-6;
    for (int c = 0; c < 3; ++c) {
      FiveBarJoints plus = q, minus = q;
      plus[c] += h;
      minus[c] -= h;
      const Vec3 d = (1.0 / (2.0 * h)) * (five_bar_tip_position(p, plus) - five_bar_tip_position(p, minus));
      worst = std::max({worst, std::abs(d.x - J[0][c]), std::abs(d.y - J[1][c]),
                        std::abs(d.z - J[2][c])});
    }
  }
  std::printf("  worst |J - finite difference| over 500 poses: %.3g m/rad\n", worst);
  EXPECT_LT(worst, 1e-8);
}

// Eqs. 5.1–5.3 give the joint torques from the end-effector-frame forces (x_e along the beam,
// y_e vertical, z_e horizontal; R of eq. 3.118). Jᵀ F reproduces eq. 5.3 exactly, eq. 5.1 once
// its force is the horizontal F_z (printed F_x, a misprint: F_x is along the beam and has no
// moment about the base axis), and eq. 5.2 exactly where q2 − q1 = 90° (home); elsewhere Jᵀ F
// adds −F_y l1 cos(q2 − q1), which eq. 5.2 drops.
TEST(FiveBarKinematics, JointTorquesMatchTheEndEffectorFormulas_Eq5_1to5_3) {
  const FiveBarParams p;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int n = 0; n < 200; ++n) {
    const FiveBarJoints q{0.5 * unit(rng), 90.0 * kDeg + 0.5 * unit(rng),
                          180.0 * kDeg + 0.5 * unit(rng)};
    const Vec3 F_W{5.0 * unit(rng), 5.0 * unit(rng), 5.0 * unit(rng)};
    const double C0 = std::cos(q[0]), S0 = std::sin(q[0]);
    const double C2 = std::cos(q[2]), S2 = std::sin(q[2]);
    // Columns of R (eq. 3.118): the end-effector axes in W.
    const Vec3 x_e{-C0 * C2, -S0 * C2, -S2}, y_e{C0 * S2, S0 * S2, -C2}, z_e{S0, -C0, 0.0};
    const auto dot = [](const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; };
    const double Fx = dot(x_e, F_W), Fy = dot(y_e, F_W), Fz = dot(z_e, F_W);
    const FiveBarJoints tau = five_bar_joint_torque(p, q, F_W);
    const double rho = p.l1 * std::cos(q[1]) - p.l_f * C2;
    EXPECT_NEAR(tau[0], -Fz * rho, 1e-12);                                     // 5.1, F_z
    EXPECT_NEAR(tau[1], -Fx * p.l1 * std::sin(q[2] - q[1]) - Fy * p.l1 * std::cos(q[2] - q[1]),
                1e-12);                                                        // 5.2 + term
    EXPECT_NEAR(tau[2], Fy * p.l_f, 1e-12);                                    // 5.3
  }
  // At home the extra term vanishes and eq. 5.2 holds as printed; so do the moment arms of
  // L2567: 61 cm (≈ l_f) horizontal and vertical, 30 cm axial.
  const FiveBarJoints tau = five_bar_joint_torque(p, five_bar_home(), {1.0, 1.0, 1.0});
  EXPECT_NEAR(tau[0], 0.6, 1e-15);
  EXPECT_NEAR(tau[1], -0.3, 1e-15);
  EXPECT_NEAR(tau[2], 0.6, 1e-15);
}

TEST(FiveBarKinematics, InverseKinematicsRoundTripsBothBranches_Eq3_118) {
  const FiveBarParams p;
  int checked[2] = {0, 0};
  double worst_q = 0.0, worst_p = 0.0;
  for (const FiveBarBranch branch : {FiveBarBranch::kElbowDown, FiveBarBranch::kElbowUp}) {
    const int b = branch == FiveBarBranch::kElbowDown ? 0 : 1;
    for (double q0 = -60.0; q0 <= 60.0; q0 += 15.0) {
      for (double q1 = 20.0; q1 <= 160.0; q1 += 10.0) {
        // q2 − q1 = γ + π with γ in (−180°, 0°) for elbow-down, (0°, 180°) for elbow-up.
        for (double gamma = 5.0; gamma <= 175.0; gamma += 10.0) {
          const double g = b == 0 ? -gamma : gamma;
          const FiveBarJoints q{q0 * kDeg, q1 * kDeg, (q1 + g + 180.0) * kDeg};
          const Vec3 tip = five_bar_tip_position(p, q);
          if (std::hypot(tip.x, tip.y) < 1e-3) continue;  // on the base axis q0 is undefined
          const double rho = p.l1 * std::cos(q[1]) - p.l_f * std::cos(q[2]);
          if (rho < 0.0) continue;  // behind the axis: IK returns the q0 + π twin
          FiveBarJoints back{};
          ASSERT_TRUE(five_bar_inverse_kinematics(p, tip, branch, back));
          for (int i = 0; i < 3; ++i) worst_q = std::max(worst_q, std::abs(wrap(back[i] - q[i])));
          const Vec3 again = five_bar_tip_position(p, back);
          worst_p = std::max({worst_p, std::abs(again.x - tip.x), std::abs(again.y - tip.y),
                              std::abs(again.z - tip.z)});
          ++checked[b];
        }
      }
    }
  }
  std::printf("  poses: %d elbow-down, %d elbow-up; worst |dq| %.3g rad, |dp| %.3g m\n",
              checked[0], checked[1], worst_q, worst_p);
  EXPECT_GT(checked[0], 500);
  EXPECT_GT(checked[1], 400);
  EXPECT_LT(worst_q, 1e-9);
  EXPECT_LT(worst_p, 1e-12);
  // Home is on the elbow-down branch (γ = −90°).
  FiveBarJoints q{};
  ASSERT_TRUE(five_bar_inverse_kinematics(p, {0.6, 0.0, 0.3}, FiveBarBranch::kElbowDown, q));
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(q[i], five_bar_home()[i], 1e-12);
  // Out of reach (beyond l1 + l_f), and on the axis.
  EXPECT_FALSE(five_bar_inverse_kinematics(p, {0.95, 0.0, 0.0}, FiveBarBranch::kElbowDown, q));
  EXPECT_FALSE(five_bar_inverse_kinematics(p, {0.0, 0.0, 0.5}, FiveBarBranch::kElbowDown, q));
}

// ---------------------------------------------------------------------------------------------
// Parameters.

TEST(FiveBarParams, DefaultsAreTable5_4AndValidateNamesTheBadParameter_Table5_4) {
  const FiveBarParams p;
  EXPECT_EQ(p.validate(), "");
  EXPECT_EQ(FiveBarParams::theoretical().validate(), "");
  // The base joint's inertia at home is Table 5.4's identified 0.733 (defaults) and Table 5.5's
  // theoretical 0.708 (to the 0.001 of 0.677 + 0.032).
  EXPECT_NEAR(FiveBarPlant(p).mass_matrix(five_bar_home())[0][0], 0.733, 1e-12);
  EXPECT_NEAR(FiveBarPlant(FiveBarParams::theoretical()).mass_matrix(five_bar_home())[0][0],
              0.708, 1.5e-3);
  const auto message = [](auto change) {
    FiveBarParams q;
    change(q);
    return q.validate();
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(message([](FiveBarParams& q) { q.l1 = 0.0; }).rfind("l1: ", 0), 0u);
  EXPECT_EQ(message([&](FiveBarParams& q) { q.alpha1 = nan; }).rfind("alpha1: ", 0), 0u);
  EXPECT_EQ(message([](FiveBarParams& q) { q.alpha2 = -0.1; }).rfind("alpha2: ", 0), 0u);
  EXPECT_EQ(message([](FiveBarParams& q) { q.alpha3 = 0.1; }).rfind("alpha3: ", 0), 0u);
  EXPECT_EQ(message([](FiveBarParams& q) { q.friction[1].coulomb = -1.0; })
                .rfind("friction[1].coulomb: ", 0),
            0u);
  EXPECT_EQ(message([](FiveBarParams& q) { q.encoder_rad_per_count[2] = 0.0; })
                .rfind("encoder_rad_per_count[2]: ", 0),
            0u);
  EXPECT_EQ(message([&](FiveBarParams& q) { q.torque_limit[0] = nan; }).rfind("torque_limit[0]: ", 0),
            0u);
  std::printf("  e.g. \"%s\"\n", message([](FiveBarParams& q) { q.alpha2 = -0.1; }).c_str());
}

// ---------------------------------------------------------------------------------------------
// Dynamics.

// Eq. 4.10: the only off-diagonal inertia is α3 C(2−1); α3 = 0 (eq. 4.6) makes D diagonal, and
// then driving q1 leaves q2 at rest (dynamic decoupling, L2362); with α3 ≠ 0 it does not.
TEST(FiveBarDynamics, Alpha3ZeroMakesTheInertiaDiagonalAndDecouples_Eq4_10) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  const FiveBarParams p = frictionless();
  const FiveBarPlant plant(p);
  for (int n = 0; n < 200; ++n) {
    const FiveBarJoints q{angle(rng), angle(rng), angle(rng)};
    const FiveBarMatrix D = plant.mass_matrix(q);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        if (r != c) {
          EXPECT_EQ(D[r][c], 0.0);
        }
      }
    }
    EXPECT_NEAR(D[0][0], p.J_hub + p.alpha1 * std::pow(std::cos(q[1]), 2) +
                             p.alpha2 * std::pow(std::cos(q[2]), 2), 1e-15);
    EXPECT_EQ(D[1][1], p.alpha1);
    EXPECT_EQ(D[2][2], p.alpha2);
  }
  const auto q2_motion = [](double alpha3) {
    FiveBarParams params = frictionless();
    params.alpha3 = alpha3;
    FiveBarPlant driven(params, {{0.0, 60.0 * kDeg, 170.0 * kDeg}, {}});
    for (int k = 0; k < 200; ++k) driven.step({0.0, 1.0, 0.0}, 1e-3);
    return std::abs(driven.state().q[2] - 170.0 * kDeg);
  };
  const double decoupled = q2_motion(0.0);
  const double coupled = q2_motion(0.02);
  std::printf("  q2 moved %.3g rad (alpha3 = 0) vs %.3g rad (alpha3 = 0.02) under 1 N·m on q1\n",
              decoupled, coupled);
  EXPECT_EQ(decoupled, 0.0);
  EXPECT_GT(coupled, 1e-3);
}

// The velocity terms of L2382 (and the α3 and tip-mass terms added here) must be the ones eq. 4.10
// implies: with no torque and no friction the kinetic energy is conserved.
TEST(FiveBarDynamics, VelocityTermsConserveKineticEnergy_L2382) {
  for (const double alpha3 : {0.0, 0.03}) {
    for (const double tip_mass : {0.0, 0.5}) {
      FiveBarParams p = frictionless();
      p.alpha3 = alpha3;
      FiveBarPlant plant(p, {five_bar_home(), {2.0, -3.0, 4.0}});
      const double e0 = plant.kinetic_energy(plant.state(), tip_mass);
      for (int k = 0; k < 1000; ++k) {
        plant.step({}, 1e-3, [](const Vec3&, const Vec3&) { return Vec3{}; }, tip_mass);
      }
      const double e1 = plant.kinetic_energy(plant.state(), tip_mass);
      std::printf("  alpha3 %.2f, tip mass %.1f kg: E %.9f -> %.9f J after 1 s\n", alpha3,
                  tip_mass, e0, e1);
      EXPECT_NEAR(e1, e0, 1e-8 * e0);
      // The joints really moved through the configuration-dependent inertia.
      EXPECT_GT(std::abs(plant.state().q[1] - five_bar_home()[1]), 0.5);
    }
  }
}

// L2388: at haptic speeds the centripetal/Coriolis terms are negligible. Measure the tip error of
// dropping them after 1 s of free motion, at a hand's speed and at a fast one.
TEST(FiveBarDynamics, DroppingCoriolisIsSmallAtHapticSpeeds_L2388) {
  const auto tip_error = [](double scale) {
    const FiveBarParams p = frictionless();
    const FiveBarState start{five_bar_home(), {scale * 0.3, scale * 0.3, scale * 0.3}};
    FiveBarPlant full(p, start);
    FiveBarPlantOptions approx_options;
    approx_options.coriolis = false;
    FiveBarPlant approx(p, start, approx_options);
    for (int k = 0; k < 1000; ++k) {
      full.step({}, 1e-3);
      approx.step({}, 1e-3);
    }
    const Vec3 d = five_bar_tip_position(p, full.state().q) - five_bar_tip_position(p, approx.state().q);
    const Vec3 travel = five_bar_tip_position(p, full.state().q) - five_bar_tip_position(p, start.q);
    return std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z) /
           std::sqrt(travel.x * travel.x + travel.y * travel.y + travel.z * travel.z);
  };
  // 0.3 rad/s per joint is ≈ 0.1–0.2 m/s at the tip (a hand's speed); 10× is a fast swing.
  const double slow = tip_error(1.0);
  const double fast = tip_error(10.0);
  std::printf("  tip error without Coriolis after 1 s, relative to the travel: %.3g %% at 0.3 rad/s, "
              "%.3g %% at 3 rad/s\n", 100.0 * slow, 100.0 * fast);
  EXPECT_LT(slow, 0.02);
  EXPECT_GT(fast, 5.0 * slow);  // the terms are quadratic in velocity
}

// Balanced (L2371–2380): no gravity term, so any pose at rest stays put with no torque.
TEST(FiveBarDynamics, BalancedPlantHoldsAnyPoseAtRest_L2380) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  for (int n = 0; n < 20; ++n) {
    const FiveBarJoints q{angle(rng), angle(rng), angle(rng)};
    FiveBarPlant plant(FiveBarParams{}, {q, {}});
    for (int k = 0; k < 1000; ++k) plant.step({}, 1e-3);
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(plant.state().q[i], q[i]);
      EXPECT_EQ(plant.state().qdot[i], 0.0);
    }
  }
}

// Table 5.4's Coulomb friction: a constant torque below f holds the joint at rest; above it the
// joint accelerates at (τ − f) / J.
TEST(FiveBarDynamics, CoulombFrictionHoldsBelowAndSlipsAbove_Table5_4) {
  const FiveBarParams p;
  const double inertia[3] = {0.733, 0.204, 0.026};  // Table 5.4's J at home
  for (int i = 0; i < 3; ++i) {
    const double f = p.friction[i].coulomb;
    for (const double sign : {1.0, -1.0}) {
      FiveBarPlant held(p);
      FiveBarJoints tau{};
      tau[i] = sign * 0.95 * f;
      for (int k = 0; k < 500; ++k) held.step(tau, 1e-3);
      EXPECT_EQ(held.state().q[i], five_bar_home()[i]) << "joint " << i;

      FiveBarPlant slipping(p);
      tau[i] = sign * 1.5 * f;
      for (int k = 0; k < 100; ++k) slipping.step(tau, 1e-3);
      const double moved = slipping.state().q[i] - five_bar_home()[i];
      const double expected = 0.5 * sign * 0.5 * f / inertia[i] * 0.1 * 0.1;
      EXPECT_NEAR(moved, expected, 0.02 * std::abs(expected)) << "joint " << i;
    }
  }
}

// Table 5.4 by the thesis' own procedure (§5.3.2): P control τ = K (r − q) from rest, first peaks
// y_p for several steps r, regression y_p = α (r − f/K); then ζ (5.8), ω_n (5.9), J = K/ω_n²,
// B = 2ζ√(KJ), f = K r0 (5.6). The plant carries Table 5.4's J, B, f, so the identification must
// return them, and the printed slope, r-intercept and t_p. K = 3.7 N·m/rad [inference: the
// thesis does not give it; ω_n² J = 3.60 / 3.74 / 3.71 across the rows].
TEST(FiveBarDynamics, FrictionIdentificationReproducesTheTable_Table5_4) {
  const FiveBarParams p;
  const double K = 3.7;
  struct Row { double slope, r0, t_p, J, B, f; };
  const Row table[3] = {{1.96, 0.034, 1.40, 0.733, 0.045, 0.125},   // horizontal q0
                        {1.98, 0.024, 0.75, 0.204, 0.012, 0.088},   // axial q1
                        {1.95, 0.022, 0.26, 0.026, 0.009, 0.082}};  // vertical q2
  const double dt = 1e-4;
  for (int i = 0; i < 3; ++i) {
    std::vector<double> r_values{0.1, 0.2, 0.3}, peaks, times;
    for (const double r : r_values) {
      FiveBarPlantOptions options;
      options.integration = {Integrator::kRk4, 1};
      FiveBarPlant plant(p, {}, options);
      const double q_start = plant.state().q[i];
      double peak = 0.0, t = 0.0;
      for (int k = 0; k < 40000; ++k) {
        FiveBarJoints tau{};
        tau[i] = K * (r - (plant.state().q[i] - q_start));
        plant.step(tau, dt);
        t += dt;
        peak = plant.state().q[i] - q_start;
        // The first peak: where the velocity first comes back to zero (after it Coulomb friction
        // may hold the joint still for good).
        if (plant.state().qdot[i] <= 0.0) break;
      }
      peaks.push_back(peak);
      times.push_back(t);
    }
    double sr = 0, sy = 0, srr = 0, sry = 0;
    for (int k = 0; k < 3; ++k) {
      sr += r_values[k]; sy += peaks[k]; srr += r_values[k] * r_values[k]; sry += r_values[k] * peaks[k];
    }
    const double alpha = (3 * sry - sr * sy) / (3 * srr - sr * sr);
    const double r0 = -(sy - alpha * sr) / 3.0 / alpha;  // where the line crosses y = 0
    const double t_p = (times[0] + times[1] + times[2]) / 3.0;
    const double beta = -std::log(alpha - 1.0);
    const double zeta = beta / std::sqrt(kPi * kPi + beta * beta);        // eq. 5.8
    const double w_n = kPi / (t_p * std::sqrt(1.0 - zeta * zeta));       // eq. 5.9
    const double J = K / (w_n * w_n);
    const double B = 2.0 * zeta * std::sqrt(K * J);
    const double f = K * r0;                                               // eq. 5.6
    std::printf("  joint %d: slope %.3f r0 %.4f t_p %.3f w_n %.3f zeta %.4f J %.4f B %.4f f %.4f\n",
                i, alpha, r0, t_p, w_n, zeta, J, B, f);
    EXPECT_NEAR(alpha, table[i].slope, 0.01) << i;  // printed to 0.01
    EXPECT_NEAR(r0, table[i].r0, 0.001) << i;       // printed to 0.001
    EXPECT_NEAR(t_p, table[i].t_p, 0.02 * table[i].t_p) << i;
    EXPECT_NEAR(J, table[i].J, 0.005 * table[i].J) << i;
    EXPECT_NEAR(B, table[i].B, 0.05 * table[i].B) << i;
    EXPECT_NEAR(f, table[i].f, 0.01 * table[i].f) << i;
  }
}

// L3237: τ_d = K_m K_a V_a = 0.373 × 3.87 × 5 = 7.218 N·m on the axial joint (printed 7.23).
TEST(FiveBarDynamics, TorqueSaturatesAtTheDacLimit_L3237) {
  const FiveBarParams p;
  FiveBarPlant plant(frictionless());
  plant.step({10.0, 10.0, -10.0}, 1e-3);
  const FiveBarJoints& applied = plant.applied_torque();
  std::printf("  10 N·m commanded -> %.4f / %.4f / %.4f N·m delivered\n", applied[0], applied[1],
              applied[2]);
  EXPECT_DOUBLE_EQ(applied[1], 0.373 * 3.87 * 5.0);
  EXPECT_NEAR(applied[1], 7.23, 0.015);
  EXPECT_DOUBLE_EQ(applied[0], 0.373 * 3.98 * 5.0);
  EXPECT_DOUBLE_EQ(applied[2], -0.373 * 3.96 * 5.0);
  // What the joint feels is the saturated torque: q1 after 1 ms is ½ (τ_d / α1) t².
  EXPECT_NEAR(plant.state().q[1] - five_bar_home()[1], 0.5 * applied[1] / p.alpha1 * 1e-6, 1e-12);
}

// ---------------------------------------------------------------------------------------------
// Sensing.

TEST(FiveBarEncoders, AxialStepIsPiOver6000_Table5_2) {
  const FiveBarParams p;
  const double expected[3] = {kPi / 6000.0, kPi / 6000.0, kPi / 4000.0};
  for (int i = 0; i < 3; ++i) {
    std::vector<double> levels;
    FiveBarJoints q = five_bar_home();
    for (int k = 0; k <= 20000; ++k) {
      q[i] = five_bar_home()[i] - 0.01 + 1e-6 * k;
      const double reading = five_bar_encoder_reading(p, q)[i];
      EXPECT_LT(std::abs(reading - q[i]), expected[i] * (1.0 + 1e-9));
      if (levels.empty() || reading != levels.back()) levels.push_back(reading);
    }
    for (std::size_t k = 1; k < levels.size(); ++k) {
      EXPECT_NEAR(levels[k] - levels[k - 1], expected[i], 1e-12) << "joint " << i;
    }
    EXPECT_GT(levels.size(), 10u);
  }
  // At home the reading is exact, and one axial count is ≈ 157 µm of tip travel at l1 (L3150).
  const FiveBarJoints home_reading = five_bar_encoder_reading(p, five_bar_home());
  for (int i = 0; i < 3; ++i) EXPECT_EQ(home_reading[i], five_bar_home()[i]);
  EXPECT_NEAR(p.l1 * kPi / 6000.0, 157e-6, 1e-6);
}

TEST(FiveBarEncoders, BackwardDifferenceLowPassTracksARamp_Eq6_2) {
  BackwardDifferenceVelocity filter;
  filter.reset({0.0, 0.0, 0.0});
  const double dt = 1e-3;
  double t = 0.0;
  FiveBarJoints v{};
  for (int k = 0; k < 50; ++k) {  // one time constant 1/ω0 = 50 ms
    t += dt;
    v = filter.update({0.1 * t, -0.2 * t, 0.0}, dt);
  }
  // First order: 1 − e^{−1} of the way after one time constant.
  EXPECT_NEAR(v[0], 0.1 * (1.0 - std::exp(-1.0)), 1e-12);
  EXPECT_NEAR(v[1], -0.2 * (1.0 - std::exp(-1.0)), 1e-12);
  for (int k = 0; k < 1000; ++k) {
    t += dt;
    v = filter.update({0.1 * t, -0.2 * t, 0.0}, dt);
  }
  EXPECT_NEAR(v[0], 0.1, 1e-9);
  EXPECT_EQ(v[2], 0.0);
}

// ---------------------------------------------------------------------------------------------
// Flexible link.

TEST(FlexibleLink, ClampedFreeFirstModeIs436RadPerSecond_Eq5_10) {
  EXPECT_NEAR(clamped_free_root(1), 1.875, 5e-4);  // B.9's first root (L2756)
  EXPECT_NEAR(clamped_free_root(2), 4.694, 5e-4);
  // The tube of §5.4: ½" square, 0.127 cm wall (L2764–2768).
  EXPECT_NEAR(square_tube_area_moment(0.0127, 0.00127), 1.28e-9, 0.005e-9);
  EXPECT_NEAR(square_tube_area(0.0127, 0.00127), 5.81e-5, 0.005e-5);
  const BeamParams beam;
  const double w1 = clamped_free_frequency(beam);
  std::printf("  clamped-free: %.2f rad/s (%.2f Hz); printed 436 rad/s, 69 Hz\n", w1,
              w1 / (2.0 * kPi));
  EXPECT_NEAR(w1, 436.0, 0.01 * 436.0);
  EXPECT_NEAR(w1 / (2.0 * kPi), 69.0, 0.01 * 69.0);
  EXPECT_NEAR(beam.rho_A * beam.length, 0.071, 0.001);  // "ρlA = 71 g" (L2774)
}

TEST(FlexibleLink, HubAndPayloadFirstModeIs223RadPerSecond_Eq5_11) {
  const HubPayloadBeamParams beam;
  EXPECT_NEAR(beam.J0 / beam.rho, 4.16, 0.01);    // Ω0 (L2820)
  EXPECT_NEAR(beam.M_p / beam.rho, 0.26, 0.005);  // Ω_p
  const double w = hub_payload_first_frequency(beam);
  std::printf("  hub + payload: %.2f rad/s (%.2f Hz); printed 223 rad/s, 35.5 Hz\n", w,
              w / (2.0 * kPi));
  EXPECT_NEAR(w, 223.0, 0.01 * 223.0);
  EXPECT_NEAR(w / (2.0 * kPi), 35.5, 0.01 * 35.5);
  EXPECT_NEAR(hub_payload_characteristic(beam, w), 0.0, 1e-9);
  // L2832: a hub 10⁶ times heavier lowers it by less than 0.4 Hz.
  HubPayloadBeamParams heavy = beam;
  heavy.J0 *= 1e6;
  const double w_heavy = hub_payload_first_frequency(heavy);
  EXPECT_LT(w_heavy, w);
  EXPECT_LT((w - w_heavy) / (2.0 * kPi), 0.4);
  // L2834: 4 cm more beam only brings it to 31 Hz.
  HubPayloadBeamParams longer = beam;
  longer.L += 0.04;
  const double w_long = hub_payload_first_frequency(longer);
  std::printf("  +4 cm: %.2f Hz (printed 31 Hz); hub x1e6: %.3f Hz lower\n",
              w_long / (2.0 * kPi), (w - w_heavy) / (2.0 * kPi));
  EXPECT_NEAR(w_long / (2.0 * kPi), 31.0, 0.5);
  // Without the payload the hub-beam mode lies above the clamped-free one (pinned-free side,
  // L2735–2737): the payload is what brings it down.
  HubPayloadBeamParams bare = beam;
  bare.M_p = 0.0;
  EXPECT_GT(hub_payload_first_frequency(bare), w);
}

// ---------------------------------------------------------------------------------------------
// The plant's flexible mode (eqs. 3.29–3.31, one mode on the base joint q0).

FiveBarPlantOptions flexible_options(double zeta = 0.02) {
  FiveBarPlantOptions options;
  options.flexible_mode = true;
  options.mode.zeta = zeta;
  return options;
}

// The defaults are the thesis' beam: ω1 from eq. 5.11, β1 and φ1(l) of the normalized
// clamped-free shape (B.8, ∫φ² = 1), checked here by quadrature rather than the closed forms.
TEST(FiveBarFlexibleMode, DefaultsAreTheThesisBeam_Eq3_31_Eq5_11) {
  const FiveBarFlexibleMode defaults;
  const FiveBarFlexibleMode beam = FiveBarFlexibleMode::from_beam(HubPayloadBeamParams{}, 0.02);
  EXPECT_EQ(defaults.omega, beam.omega);
  EXPECT_EQ(defaults.beta, beam.beta);
  EXPECT_EQ(defaults.tip_shape, beam.tip_shape);
  EXPECT_EQ(defaults.rho, beam.rho);
  EXPECT_EQ(defaults.zeta, 0.02);
  EXPECT_NEAR(defaults.omega, 222.31, 0.005);
  const double l = HubPayloadBeamParams{}.L;
  const int n = 20000;
  double norm = 0.0, beta = 0.0;
  for (int i = 0; i < n; ++i) {  // midpoint rule
    const double x = (i + 0.5) * l / n;
    const double phi = clamped_free_shape(1, x, l);
    norm += phi * phi * l / n;
    beta += x * phi * l / n;
  }
  std::printf("  beta1 %.6f m^1.5 (quadrature %.6f), phi1(l) %.6f m^-0.5, int phi^2 %.9f\n",
              defaults.beta, beta, defaults.tip_shape, norm);
  EXPECT_NEAR(norm, 1.0, 1e-8);
  EXPECT_NEAR(defaults.beta, beta, 1e-8);
  EXPECT_NEAR(defaults.tip_shape, 2.0 / std::sqrt(l), 1e-12);
  EXPECT_NEAR(clamped_free_tip_value(2, l), -2.0 / std::sqrt(l), 1e-9);  // 2 (−1)^(k+1) / √l
  EXPECT_EQ(defaults.validate(), "");
  FiveBarFlexibleMode bad_mode;
  bad_mode.zeta = -0.1;
  EXPECT_EQ(bad_mode.validate().rfind("mode.zeta: ", 0), 0u);
}

// The linearized hub + mode of eq. 3.31 at home, M̄ = [[D00, ρβ1], [ρβ1, ρ]], K = diag(0, ρω1²):
// det(K − Ω² M̄) = 0, solved as a 2×2 generalized eigenproblem (independent of the plant code).
double coupled_frequency(const FiveBarParams& p, const FiveBarFlexibleMode& mode) {
  const double C1 = std::cos(five_bar_home()[1]), C2 = std::cos(five_bar_home()[2]);
  const double M[2][2] = {{p.J_hub + p.alpha1 * C1 * C1 + p.alpha2 * C2 * C2, mode.rho * mode.beta},
                          {mode.rho * mode.beta, mode.rho}};
  const double K[2][2] = {{0.0, 0.0}, {0.0, mode.rho * mode.omega * mode.omega}};
  // det(K − λM) = a λ² + b λ + c.
  const double a = M[0][0] * M[1][1] - M[0][1] * M[1][0];
  const double b = -(K[0][0] * M[1][1] + K[1][1] * M[0][0] - K[0][1] * M[1][0] - K[1][0] * M[0][1]);
  const double c = K[0][0] * K[1][1] - K[0][1] * K[1][0];
  const double lambda = (-b + std::sqrt(b * b - 4.0 * a * c)) / (2.0 * a);
  return std::sqrt(lambda);
}

struct Ring {
  std::vector<double> t, eta, hub_rate;
  double momentum_error = 0.0;  // worst |p0 − impulse| / impulse after the impulse
};

// A 5 N·m, 1 ms torque pulse on q0 of the frictionless plant at home, then 0.4 s free, sampled at
// 10 kHz (RK4, h = 100 µs).
Ring ring_after_hub_impulse(double zeta) {
  const FiveBarParams p = frictionless();
  FiveBarPlantOptions options = flexible_options(zeta);
  options.integration = {Integrator::kRk4, 1};
  FiveBarPlant plant(p, {}, options);
  const double dt = 1e-4, torque = 5.0, pulse = 1e-3;
  Ring ring;
  for (int k = 0; k < 4010; ++k) {
    const bool on = k < 10;
    plant.step({on ? torque : 0.0, 0.0, 0.0}, dt);
    if (on) continue;
    const FiveBarState& s = plant.state();
    const FiveBarModeState& m = plant.mode_state();
    ring.t.push_back((k + 1) * dt);
    ring.eta.push_back(m.eta);
    ring.hub_rate.push_back(s.qdot[0]);
    // No torque on q0 after the pulse: ∂L/∂q̇0 = (D00 + ρη²) q̇0 + ρβ1 η̇ (eq. 3.29) stays at the
    // impulse.
    const FiveBarFlexibleMatrix M = plant.flexible_mass_matrix(s.q, m.eta);
    const double p0 = M[0][0] * s.qdot[0] + M[0][3] * m.eta_dot;
    const double impulse = torque * pulse;
    ring.momentum_error = std::max(ring.momentum_error, std::abs(p0 - impulse) / impulse);
  }
  return ring;
}

// Frequency from the zero crossings of a signal (linear interpolation between samples).
double crossing_frequency(const std::vector<double>& t, const std::vector<double>& x) {
  std::vector<double> crossings;
  for (std::size_t k = 1; k < x.size(); ++k) {
    if ((x[k - 1] < 0.0) != (x[k] < 0.0)) {
      crossings.push_back(t[k - 1] + (t[k] - t[k - 1]) * x[k - 1] / (x[k - 1] - x[k]));
    }
  }
  if (crossings.size() < 3) return 0.0;
  return kPi * static_cast<double>(crossings.size() - 1) / (crossings.back() - crossings.front());
}

TEST(FiveBarFlexibleMode, HubImpulseRingsAtTheCoupledFrequency_Eq3_31) {
  const FiveBarFlexibleMode mode;
  const double predicted = coupled_frequency(frictionless(), mode);
  const Ring ring = ring_after_hub_impulse(mode.zeta);
  const double from_eta = crossing_frequency(ring.t, ring.eta);
  // The hub rate rings about its mean drift: subtract the mean over whole samples.
  std::vector<double> hub = ring.hub_rate;
  double mean = 0.0;
  for (const double v : hub) mean += v / static_cast<double>(hub.size());
  for (double& v : hub) v -= mean;
  const double from_hub = crossing_frequency(ring.t, hub);
  // ζ lowers the ringing to Ω √(1 − ζ_c²), 0.02 % here (see the next test for ζ_c).
  const double D00 = frictionless().J_hub + frictionless().alpha2;
  const double zeta_c = mode.zeta / std::sqrt(1.0 - mode.rho * mode.beta * mode.beta / D00);
  std::printf("  coupled prediction %.3f rad/s (%.3f Hz; damped %.3f; omega1 with the hub held "
              "%.3f); measured from eta %.3f, from the hub rate %.3f rad/s; momentum error %.2g\n",
              predicted, predicted / (2.0 * kPi), predicted * std::sqrt(1.0 - zeta_c * zeta_c),
              mode.omega, from_eta, from_hub, ring.momentum_error);
  EXPECT_NEAR(from_eta, predicted, 0.02 * predicted);
  EXPECT_NEAR(from_hub, predicted, 0.02 * predicted);
  // Tighter than the hub-held ω1 is from the prediction (0.33 %), so the coupling is what rings.
  EXPECT_NEAR(from_eta, predicted, 1e-3 * predicted);
  EXPECT_LT(ring.momentum_error, 1e-9);
}

// Eq. 3.30 with the modal damping 2ζω1ρη̇: with the hub free (no torque, no friction) the mode is
// the one-degree oscillator ρ(1 − ρβ1²/D00) η̈ + 2ζω1ρ η̇ + ρω1² η = 0 (momentum eliminated), so
// its damping ratio is ζ_c = ζ / √(1 − ρβ1²/D00) and the log decrement 2πζ_c / √(1 − ζ_c²).
TEST(FiveBarFlexibleMode, ModeDecaysAtTheStatedDamping_Eq3_30) {
  const FiveBarParams p = frictionless();
  const FiveBarFlexibleMode mode;
  const double D00 = p.J_hub + p.alpha2;  // at home: C1 = 0, C2 = −1
  const double zeta_c = mode.zeta / std::sqrt(1.0 - mode.rho * mode.beta * mode.beta / D00);
  const double expected = 2.0 * kPi * zeta_c / std::sqrt(1.0 - zeta_c * zeta_c);
  const Ring ring = ring_after_hub_impulse(mode.zeta);
  // Positive peaks of η, refined by a parabola through the three samples around each.
  std::vector<double> peaks;
  for (std::size_t k = 1; k + 1 < ring.eta.size(); ++k) {
    const double a = ring.eta[k - 1], b = ring.eta[k], c = ring.eta[k + 1];
    if (b > 0.0 && b >= a && b > c) {
      const double curvature = a - 2.0 * b + c;
      peaks.push_back(b - 0.125 * (a - c) * (a - c) / curvature);
    }
  }
  ASSERT_GE(peaks.size(), 12u);
  const std::size_t cycles = 10;
  const double measured = std::log(peaks[1] / peaks[1 + cycles]) / static_cast<double>(cycles);
  std::printf("  log decrement over %zu cycles: %.5f (expected %.5f, zeta %.3f, coupled %.5f); "
              "energy ratio per cycle %.4f\n",
              cycles, measured, expected, mode.zeta, zeta_c, std::exp(-2.0 * measured));
  EXPECT_NEAR(measured, expected, 0.05 * expected);
}

// With ζ = 0, no friction and no torque the Lagrangian of eqs. 3.29–3.31 (links + mode + coupling
// + strain, a tip mass included) has no dissipation: RK4 must hold the total energy over 1 s.
TEST(FiveBarFlexibleMode, UndampedTotalEnergyIsConserved_Eq3_31) {
  struct Case {
    FiveBarJoints qdot;
    double deflection;  // initial tip deflection φ1(l) η, m
    double tip_mass;    // kg
  };
  const Case cases[] = {{{2.0, -3.0, 4.0}, 2e-3, 0.0},
                        {{2.0, -3.0, 4.0}, 2e-3, 0.5},
                        {{0.3, -0.3, 0.3}, 5e-3, 0.0},
                        {{0.3, -0.3, 0.3}, 5e-3, 0.5}};
  for (const Case& c : cases) {
    const FiveBarPlantOptions options = flexible_options(0.0);
    FiveBarPlant plant(frictionless(), {five_bar_home(), c.qdot}, options);
    plant.set_mode_state({c.deflection / options.mode.tip_shape, 0.0});
    const auto strain = [&](const FiveBarPlant& at) {
      const double eta = at.mode_state().eta;
      return 0.5 * options.mode.rho * options.mode.omega * options.mode.omega * eta * eta;
    };
    const double e0 = plant.flexible_energy(plant.state(), plant.mode_state(), c.tip_mass);
    double worst = 0.0, strain_max = 0.0;
    for (int k = 0; k < 1000; ++k) {
      plant.step({}, 1e-3, [](const Vec3&, const Vec3&) { return Vec3{}; }, c.tip_mass);
      const double e = plant.flexible_energy(plant.state(), plant.mode_state(), c.tip_mass);
      worst = std::max(worst, std::abs(e - e0) / e0);
      strain_max = std::max(strain_max, strain(plant));
    }
    std::printf("  qdot0 %.1f rad/s, tip mass %.1f kg: E0 %.6g J, peak strain energy %.3g J, "
                "worst |dE|/E over 1 s %.2g\n",
                c.qdot[0], c.tip_mass, e0, strain_max, worst);
    EXPECT_LT(worst, 1e-6);
    EXPECT_GT(std::abs(plant.state().q[1] - five_bar_home()[1]), 0.2);  // the links really moved
  }
}

// A constant sideways push at the tip below the hub's Coulomb friction: the hub holds still
// (friction acts on the η-eliminated torque) and the link settles at the model's static
// deflection φ1(l)² F / (ρω1²) (eq. 3.30 at rest: ρω1² η = φ1(l) n·F).
TEST(FiveBarFlexibleMode, SidewaysPushDeflectsTheLinkWhileFrictionHoldsTheHub_Eq3_30) {
  const FiveBarParams p;  // Table 5.4's friction: the hub holds 0.125 N·m
  const FiveBarPlantOptions options = flexible_options(0.5);  // well damped, to settle fast
  FiveBarPlant plant(p, {}, options);
  const double F = 0.15;  // N along +y = n at home: 0.09 N·m about q0 < 0.125 N·m
  for (int k = 0; k < 300; ++k) {
    plant.step({}, 1e-3, [&](const Vec3&, const Vec3&) { return Vec3{0.0, F, 0.0}; });
  }
  const double expected = options.mode.tip_shape * options.mode.tip_shape * F /
                          (options.mode.rho * options.mode.omega * options.mode.omega);
  Vec3 p_WT, v_WT;
  plant.physical_tip_state(p_WT, v_WT);
  std::printf("  deflection %.4f mm under %.2f N (model %.4f mm, %.3f mm/N); hub moved %.3g rad\n",
              1e3 * p_WT.y, F, 1e3 * expected, 1e3 * expected / F,
              plant.state().q[0] - five_bar_home()[0]);
  EXPECT_EQ(plant.state().q[0], five_bar_home()[0]);
  EXPECT_NEAR(p_WT.y, expected, 1e-6 * expected);
  EXPECT_NEAR(p_WT.x, 0.6, 1e-6);  // the bend is sideways (first order)
}

// Mode off: the rigid plant as it was before the flexible path existed, bit for bit. The values
// were recorded from the rigid plant (x86-64, IEEE doubles) on a scenario that exercises friction,
// the tip force, a tip mass and two integrators.
TEST(FiveBarFlexibleMode, ModeOffIsTheRigidPlantBitForBit) {
  const FiveBarJoints recorded[2][2] = {
      {{0x1.1f3c758cbc51ap-5, 0x1.a75e41359001dp+0, 0x1.941f144c07b21p+1},
       {-0x1.442ac40b347b7p-2, -0x1.2069da81125dap-1, -0x1.d48e105b22a2dp-6}},
      {{0x1.1ec3645e4fdf3p-5, 0x1.a7557431c1f5cp+0, 0x1.941ea43bb362ap+1},
       {-0x1.4465e543d756p-2, -0x1.206fa552bcbedp-1, -0x1.cf21b7ae3e3bdp-6}}};
  const auto run = [](const FiveBarPlantOptions& options) {
    FiveBarPlant plant(FiveBarParams{}, {five_bar_home(), {0.2, -0.1, 0.3}}, options);
    const Vec3 anchor{0.58, 0.02, 0.31};
    for (int k = 0; k < 500; ++k) {
      const double t = 1e-3 * k;
      const auto hand = [&](const Vec3& p, const Vec3& v) {
        return -200.0 * (p - anchor) - 2.0 * v;
      };
      plant.step({0.5 * std::sin(7.0 * t), 0.3 * std::cos(5.0 * t), -0.2}, 1e-3, hand, 0.3);
    }
    return plant;
  };
  for (int variant = 0; variant < 2; ++variant) {
    FiveBarPlantOptions options;
    if (variant == 1) options.integration = {Integrator::kSemiImplicitEuler, 3};
    options.flexible_mode = false;
    options.mode.omega = 50.0;  // ignored when the mode is off
    const FiveBarPlant plant = run(options);
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(plant.state().q[i], recorded[variant][0][i]) << variant << " q" << i;
      EXPECT_EQ(plant.state().qdot[i], recorded[variant][1][i]) << variant << " qdot" << i;
    }
    EXPECT_EQ(plant.mode_state().eta, 0.0);
    Vec3 p_physical, v_physical, p_rigid, v_rigid;
    plant.physical_tip_state(p_physical, v_physical);
    plant.tip_state(plant.state(), p_rigid, v_rigid);
    EXPECT_EQ(p_physical, p_rigid);
    EXPECT_EQ(v_physical, v_rigid);
  }
  // And the flexible path reduces to it as the link stiffens: the tip gap falls as 1/ω1².
  const auto gap = [&](double omega) {
    FiveBarPlantOptions rigid_options;
    FiveBarPlantOptions stiff = flexible_options(0.02);
    stiff.mode.omega = omega;
    const FiveBarPlant rigid = run(rigid_options);
    const FiveBarPlant flexible = run(stiff);
    Vec3 a, b, va, vb;
    rigid.physical_tip_state(a, va);
    flexible.physical_tip_state(b, vb);
    return norm(a - b);
  };
  const double gap1 = gap(1000.0), gap2 = gap(2000.0);
  std::printf("  tip gap to the rigid plant after 0.5 s: %.3g m (omega1 1000 rad/s), "
              "%.3g m (2000)\n", gap1, gap2);
  EXPECT_LT(gap1, 1e-3);
  EXPECT_LT(gap2, 0.4 * gap1);
}

}  // namespace
}  // namespace haptic::engine
