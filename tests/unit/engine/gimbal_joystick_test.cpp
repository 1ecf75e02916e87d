// Document 004 (Russo 1990, a 3-DOF gimbal joystick with motors and magnetic-particle brakes):
// kinematics (eqs. 3.1–3.22), the cable transmission's Coulomb decay (eqs. 3.38–3.44), the contact
// model (eqs. 4.4–4.5), the hybrid motor/brake rule (eqs. 4.6–4.9, L1011, Fig. 4.10), the
// watchdog (L1930) and the actuator lags (L378, L381).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "engine/analysis/contact_stability.hpp"
#include "engine/analysis/routh.hpp"
#include "engine/control/brake_rule.hpp"
#include "engine/control/force_servo.hpp"
#include "engine/control/joystick_watchdog.hpp"
#include "engine/device/gimbal_joystick.hpp"

namespace haptic::engine {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kR = 0.009525;  // drive-pulley radius, m (code L2297)
namespace js = joystick_state;

/// Grid over the workspace: |θ|, |Φ| ≤ π/4, R in [0.1651, 0.3175] m.
template <typename Fn>
void for_each_pose(Fn&& fn) {
  for (int i = -4; i <= 4; ++i) {
    for (int j = -4; j <= 4; ++j) {
      for (const double R : {0.1651, 0.2, 0.26, 0.3175}) {
        fn(JoystickPose{i * kPi / 16.0, j * kPi / 16.0, R});
      }
    }
  }
}

double det3(const JoystickMatrix& m) {
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
         m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

JoystickMatrix product(const JoystickMatrix& a, const JoystickMatrix& b) {
  JoystickMatrix c{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) c[i][j] += a[i][k] * b[k][j];
  return c;
}

JoystickMatrix transpose(const JoystickMatrix& a) {
  JoystickMatrix t{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) t[i][j] = a[j][i];
  return t;
}

/// ∂x/∂(θ, Φ, Ψ) by central differences of eq. 3.3 (R = r Ψ).
JoystickMatrix finite_difference_jacobian(const JoystickPose& q, double h) {
  const double psi = q.R / kR;
  JoystickMatrix J{};
  for (int c = 0; c < 3; ++c) {
    double plus[3] = {q.theta, q.phi, psi};
    double minus[3] = {q.theta, q.phi, psi};
    plus[c] += h;
    minus[c] -= h;
    const Vec3 a = joystick_forward({plus[0], plus[1], kR * plus[2]});
    const Vec3 b = joystick_forward({minus[0], minus[1], kR * minus[2]});
    const Vec3 d = (1.0 / (2.0 * h)) * (a - b);
    J[0][c] = d.x;
    J[1][c] = d.y;
    J[2][c] = d.z;
  }
  return J;
}

// ---------------------------------------------------------------------------------------------
// Parameters.

TEST(GimbalJoystickParams, DefaultsAreValidAndValidateNamesTheBadParameter) {
  EXPECT_EQ(GimbalJoystickParams{}.validate(), "");
  const auto message = [](auto change) {
    GimbalJoystickParams p;
    change(p);
    return p.validate();
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(message([](GimbalJoystickParams& p) { p.M_s = -0.1; }).rfind("M_s: ", 0), 0u);
  EXPECT_EQ(message([](GimbalJoystickParams& p) { p.M_m = 0.0; }).rfind("M_m: ", 0), 0u);
  EXPECT_EQ(message([&](GimbalJoystickParams& p) { p.I_theta = nan; }).rfind("I_theta: ", 0), 0u);
  EXPECT_EQ(message([&](GimbalJoystickParams& p) { p.k_t = nan; }).rfind("k_t: ", 0), 0u);
  EXPECT_EQ(message([](GimbalJoystickParams& p) { p.F_d = -1.0; }).rfind("F_d: ", 0), 0u);
  EXPECT_EQ(message([](GimbalJoystickParams& p) { p.R_max = 0.1; }).rfind("R_max: ", 0), 0u);
  EXPECT_EQ(message([](GimbalJoystickParams& p) { p.gimbal_limit = kPi / 2; }).rfind("gimbal_limit: ", 0), 0u);
  EXPECT_EQ(message([](GimbalJoystickParams& p) { p.brake_residual_gimbal = 8.0; })
                .rfind("brake_residual_gimbal: ", 0),
            0u);
  std::printf("  e.g. \"%s\"\n", message([](GimbalJoystickParams& p) { p.M_s = -0.1; }).c_str());

  const GimbalJoystickParams p;
  JoystickActuatorCommand command;
  EXPECT_EQ(command.validate(p), "");
  command.brake[0] = 9.0;  // above the 7.78 N·m gimbal brake
  EXPECT_EQ(command.validate(p).rfind("brake[0]: ", 0), 0u) << command.validate(p);
  command.brake[0] = 7.78;
  EXPECT_EQ(command.validate(p), "");
  command.brake[2] = 1.2;  // above the 1.15 N·m shaft brake
  EXPECT_EQ(command.validate(p).rfind("brake[2]: ", 0), 0u);
  command.brake[2] = -0.1;
  EXPECT_EQ(command.validate(p).rfind("brake[2]: ", 0), 0u);
  command.brake[2] = 0.0;
  command.motor[1] = nan;
  EXPECT_EQ(command.validate(p).rfind("motor[1]: ", 0), 0u);
  std::printf("  e.g. \"%s\"\n", JoystickActuatorCommand{{}, {9.0, 0.0, 0.0}}.validate(p).c_str());

  EXPECT_EQ(CableTransmissionParams{}.validate(), "");
  CableTransmissionParams c;
  c.m_s = -1.0;
  EXPECT_EQ(c.validate().rfind("m_s: ", 0), 0u);
}

// ---------------------------------------------------------------------------------------------
// Kinematics.

TEST(GimbalKinematics, ForwardInverseRoundTripOverTheWorkspace_Eq3_1_Eq3_3) {
  double worst = 0.0;
  int poses = 0;
  for_each_pose([&](const JoystickPose& q) {
    const Vec3 x = joystick_forward(q);
    // Eq. 3.2, the tangent form, as an independent statement of the forward map.
    const double d = std::sqrt(std::tan(q.phi) * std::tan(q.phi) + 1.0 / std::pow(std::cos(q.theta), 2));
    EXPECT_NEAR(x.x, q.R * std::tan(q.theta) / d, 1e-14);
    EXPECT_NEAR(x.y, -q.R * std::tan(q.phi) / d, 1e-14);
    EXPECT_NEAR(x.z, q.R / d, 1e-14);
    const JoystickPose back = joystick_inverse(x);
    worst = std::max({worst, std::abs(back.theta - q.theta), std::abs(back.phi - q.phi),
                      std::abs(back.R - q.R)});
    ++poses;
  });
  std::printf("  %d poses, worst round-trip error %.3g\n", poses, worst);
  EXPECT_LT(worst, 1e-14);
}

TEST(GimbalKinematics, JacobianMatchesCentralDifferencesAndCorrectsTwoPrintedSigns_Eq3_13) {
  double worst = 0.0;
  int printed_23_wrong = 0, printed_31_wrong = 0, nonzero = 0;
  for_each_pose([&](const JoystickPose& q) {
    const double psi = q.R / kR;
    const JoystickMatrix J = joystick_jacobian(q.theta, q.phi, psi, kR);
    const JoystickMatrix fd = finite_difference_jacobian(q, 1e-6);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const double scale = std::max(1.0, std::abs(fd[i][j]));
        worst = std::max(worst, std::abs(J[i][j] - fd[i][j]) / scale);
      }
    // As printed: (2,3) = +r sΦ cθ / A and (3,1) = +rΨ sθ cΦ³ / A³.
    const double st = std::sin(q.theta), ct = std::cos(q.theta);
    const double sp = std::sin(q.phi), cp = std::cos(q.phi);
    const double A = std::sqrt(1.0 - st * st * sp * sp);
    const double printed_23 = kR * sp * ct / A;
    const double printed_31 = kR * psi * st * cp * cp * cp / (A * A * A);
    if (std::abs(printed_23) > 1e-6 && std::abs(printed_31) > 1e-6) {
      ++nonzero;
      printed_23_wrong += std::abs(printed_23 + fd[1][2]) < 1e-6 * std::abs(printed_23) + 1e-9;
      printed_31_wrong += std::abs(printed_31 + fd[2][0]) < 1e-6 * std::abs(printed_31) + 1e-9;
    }
  });
  std::printf("  worst |J - J_fd| (relative) %.3g; printed (2,3), (3,1) are the negatives of the "
              "differences at %d / %d and %d / %d poses\n",
              worst, printed_23_wrong, nonzero, printed_31_wrong, nonzero);
  EXPECT_LT(worst, 1e-7);
  EXPECT_EQ(printed_23_wrong, nonzero);
  EXPECT_EQ(printed_31_wrong, nonzero);
}

TEST(GimbalKinematics, DeterminantFormulaAndInverse_Eq3_15_Eq3_19) {
  double worst_det = 0.0, worst_inverse = 0.0;
  for_each_pose([&](const JoystickPose& q) {
    const double psi = q.R / kR;
    const JoystickMatrix J = joystick_jacobian(q.theta, q.phi, psi, kR);
    const double det = joystick_jacobian_determinant(q.theta, q.phi, psi, kR);
    const double numeric = det3(finite_difference_jacobian(q, 1e-6));
    worst_det = std::max(worst_det, std::abs(det - numeric) / std::abs(numeric));
    EXPECT_LT(det, 0.0);  // never zero inside ±π/4 (singular only at ±π/2)
    const JoystickMatrix I = product(joystick_jacobian_inverse(q.theta, q.phi, psi, kR), J);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) worst_inverse = std::max(worst_inverse, std::abs(I[i][j] - (i == j)));
    const JoystickMatrix inv = joystick_jacobian_inverse(q.theta, q.phi, psi, kR);
    EXPECT_EQ(inv[0][1], 0.0);  // X velocity drives θ only, Y velocity Φ only (L646)
    EXPECT_EQ(inv[1][0], 0.0);
  });
  std::printf("  det J: worst relative gap to det(J_fd) %.3g; |J^-1 J - I| max %.3g\n", worst_det,
              worst_inverse);
  EXPECT_LT(worst_det, 1e-7);
  EXPECT_LT(worst_inverse, 1e-12);
  // Singular at θ = π/2 (eq. 3.15).
  EXPECT_LT(std::abs(joystick_jacobian_determinant(kPi / 2, 0.3, 20.0, kR)),
            1e-15 * std::abs(joystick_jacobian_determinant(0.0, 0.3, 20.0, kR)));
}

TEST(GimbalKinematics, LoadCellFrameIsARotation_Eq3_10) {
  double worst = 0.0;
  for_each_pose([&](const JoystickPose& q) {
    const JoystickMatrix T = joystick_load_cell_rotation(q.theta, q.phi);
    const JoystickMatrix TTt = product(T, transpose(T));
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) worst = std::max(worst, std::abs(TTt[i][j] - (i == j)));
    EXPECT_NEAR(det3(T), 1.0, 1e-14);
    // The third row is the shaft direction (eq. 3.5): T x = (0, 0, R).
    const Vec3 Tx = joystick_multiply(T, joystick_forward(q));
    EXPECT_NEAR(Tx.x, 0.0, 1e-14);
    EXPECT_NEAR(Tx.y, 0.0, 1e-14);
    EXPECT_NEAR(Tx.z, q.R, 1e-14);
  });
  std::printf("  max |T T^T - I| %.3g\n", worst);
  EXPECT_LT(worst, 1e-14);
}

TEST(GimbalKinematics, MeasuredForceMapIsJtTtWithTheCorrectedSign_Eq3_21) {
  int printed_wrong = 0, nonzero = 0;
  for_each_pose([&](const JoystickPose& q) {
    const double psi = q.R / kR;
    const JoystickMatrix expected = product(transpose(finite_difference_jacobian(q, 1e-6)),
                                            transpose(joystick_load_cell_rotation(q.theta, q.phi)));
    const JoystickMatrix M = joystick_measured_force_to_torque(q.theta, q.phi, psi, kR);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) EXPECT_NEAR(M[i][j], expected[i][j], 1e-8);
    const double st = std::sin(q.theta), ct = std::cos(q.theta), sp = std::sin(q.phi);
    const double A2 = 1.0 - st * st * sp * sp;
    const double printed_21 = q.R * st * sp * ct / A2;
    if (std::abs(printed_21) > 1e-6) {
      ++nonzero;
      printed_wrong += std::abs(printed_21 + expected[1][0]) < 1e-7;
    }
  });
  std::printf("  printed (2,1) is the negative of Jt Tt at %d / %d poses\n", printed_wrong, nonzero);
  EXPECT_EQ(printed_wrong, nonzero);
}

// τ = Jᵀ F (eq. 3.18) against v from central differences of eq. 3.3: τ·q̇ = F·v everywhere.
TEST(GimbalKinematics, JointPowerEqualsCartesianPower_Eq3_16) {
  double worst = 0.0;
  int cases = 0;
  for_each_pose([&](const JoystickPose& q) {
    const double psi = q.R / kR;
    const JoystickMatrix J = joystick_jacobian(q.theta, q.phi, psi, kR);
    const Vec3 F{1.3, -0.7, 2.1};
    const Vec3 tau = joystick_multiply_transposed(J, F);
    for (const Vec3 q_dot : {Vec3{1.0, 0.0, 0.0}, Vec3{0.0, 1.0, 0.0}, Vec3{0.0, 0.0, 10.0},
                             Vec3{0.4, -0.9, -7.0}}) {
      const double h = 1e-6;
      const Vec3 a = joystick_forward({q.theta + h * q_dot.x, q.phi + h * q_dot.y, kR * (psi + h * q_dot.z)});
      const Vec3 b = joystick_forward({q.theta - h * q_dot.x, q.phi - h * q_dot.y, kR * (psi - h * q_dot.z)});
      const Vec3 v = (1.0 / (2.0 * h)) * (a - b);
      const double joint = dot(tau, q_dot), cartesian = dot(F, v);
      worst = std::max(worst, std::abs(joint - cartesian) / std::max(1.0, std::abs(cartesian)));
      ++cases;
      // The load-cell route gives the same power: τ = Jᵀ Tᵀ F_m with F_m = T F (eq. 3.20).
      const Vec3 F_m = joystick_multiply(joystick_load_cell_rotation(q.theta, q.phi), F);
      const Vec3 tau_m = joystick_multiply(joystick_measured_force_to_torque(q.theta, q.phi, psi, kR), F_m);
      EXPECT_NEAR(dot(tau_m, q_dot), cartesian, 1e-8);
    }
  });
  std::printf("  %d cases, worst |tau.qdot - F.v| (relative) %.3g\n", cases, worst);
  EXPECT_LT(worst, 1e-8);
}

// ---------------------------------------------------------------------------------------------
// Eq. 3.38 (cleaned): released from rest at Ψ0, the amplitude falls by 2 F_d/(k r) every half
// cycle (eq. 3.42), the velocity is zero at t = nπ/ω_n (eq. 3.41), and the motion stops at the
// first turning point inside ±F_d/(k r) (eq. 3.44, corrected: as printed, |Ψ0 − n F_d/(kr)| k < F_d
// mixes units and drops the factor 2 and r).
TEST(CableTransmission, CoulombDecayIsTwoFdOverKrPerHalfCycle_Eq3_42) {
  const CableTransmissionParams p;
  const double band = p.friction_band();
  const double w_n = p.natural_frequency();
  const double psi0 = 0.1;  // rad: 0.95 mm of shaft
  CableTransmissionModel model(p, {Integrator::kRk4, 1}, psi0);
  const double dt = 1e-6;
  std::vector<double> turn_psi, turn_t;
  double prev_v = 0.0, t = 0.0;
  bool moving = false;
  for (int k = 0; k < 60000; ++k) {  // 60 ms ≈ 16 half periods
    model.step(0.0, dt);
    t += dt;
    const double v = model.psi_dot();
    if (moving && (v == 0.0 || (v > 0.0) != (prev_v > 0.0))) {
      turn_psi.push_back(model.psi());
      turn_t.push_back(t);
    }
    moving = v != 0.0;
    prev_v = v;
  }
  // Expected: Ψ_n = (−1)ⁿ (Ψ0 − 2 n band) until |Ψ_n| ≤ band.
  int expected_turns = 0;
  while (std::abs(psi0 - 2.0 * expected_turns * band) > band) ++expected_turns;
  std::printf("  band F_d/(kr) = %.6g rad, w_n = %.2f rad/s, %zu turning points (expected %d)\n",
              band, w_n, turn_psi.size(), expected_turns);
  ASSERT_EQ(static_cast<int>(turn_psi.size()), expected_turns);
  for (int n = 1; n <= expected_turns; ++n) {
    const double expected = (n % 2 ? -1.0 : 1.0) * (psi0 - 2.0 * n * band);
    std::printf("  half cycle %d: psi %.7f (expected %.7f), t %.6f ms (n pi / w_n %.6f ms)\n", n,
                turn_psi[n - 1], expected, 1e3 * turn_t[n - 1], 1e3 * n * kPi / w_n);
    EXPECT_NEAR(turn_psi[n - 1], expected, 1e-6);
    EXPECT_NEAR(turn_t[n - 1], n * kPi / w_n, 2e-6);
  }
  EXPECT_LE(std::abs(model.psi()), band);
  EXPECT_EQ(model.psi_dot(), 0.0);
  EXPECT_NEAR(model.psi(), turn_psi.back(), 1e-12);  // stays where it stopped
}

// ---------------------------------------------------------------------------------------------
// Eqs. 4.4–4.5.

TEST(ContactStability, TransferFunctionIsTheTwoMassHandModel_Eq4_4) {
  const ContactModelParams p;
  const ContactTransferFunction tf = contact_transfer_function(p);
  for (const double w : {1.0, 41.0, 300.0, 1200.0, 5000.0}) {
    // Independently: M_m s² X_m = F_m − Z_t (X_m − X_s), M_s s² X_s = Z_t (X_m − X_s) − Z_h X_s,
    // F_c = Z_h X_s, solved for F_m = 1.
    const std::complex<double> s(0.0, w);
    const std::complex<double> Zt = p.b_t * s + p.k_t, Zh = p.b_h * s + p.k_h;
    const std::complex<double> a11 = p.M_m * s * s + Zt, a12 = -Zt, a21 = -Zt;
    const std::complex<double> a22 = p.M_s * s * s + Zt + Zh;
    const std::complex<double> X_s = -a21 / (a11 * a22 - a12 * a21);
    const std::complex<double> direct = Zh * X_s;
    EXPECT_LT(std::abs(evaluate(tf, s) - direct), 1e-10 * std::abs(direct)) << w;
  }
  // The rigid model (eq. 4.3) has unit static gain like eq. 4.4.
  EXPECT_NEAR(std::abs(evaluate(rigid_contact_transfer_function(p), {0.0, 0.0})), 1.0, 1e-15);
  EXPECT_NEAR(std::abs(evaluate(tf, {0.0, 0.0})), 1.0, 1e-15);
}

TEST(ContactStability, FirstBreakpointIs41RadPerSecondWithTheChosenMasses_Eq4_5) {
  const GimbalJoystickParams plant;
  ContactModelParams p;
  p.M_m = plant.M_m;
  p.M_s = plant.M_s;
  EXPECT_EQ(p.validate(), "");
  const ContactBreakpoints b = contact_breakpoints(p);
  std::printf("  M_m %.2f kg, M_s %.2f kg: omega1 %.3f rad/s, omega2 %.1f rad/s\n", p.M_m, p.M_s,
              b.omega1, b.omega2);
  EXPECT_NEAR(b.omega1, 41.0, 0.5);  // "the smaller of the two roots is ω1 = 41 rad/sec" (L940)
  // Both are roots of the denominator's real part at s = jω (the breakpoint definition).
  const ContactTransferFunction tf = contact_transfer_function(p);
  for (const double w : {b.omega1, b.omega2}) {
    const double even = tf.denominator[0] * std::pow(w, 4) - tf.denominator[2] * w * w + tf.denominator[4];
    EXPECT_NEAR(even / tf.denominator[4], 0.0, 1e-9) << w;
  }
  // The formula as printed, ω = √a ± √(a² − …), gives a negative "ω1" for these values.
  const double mm = p.M_m * p.M_s;
  const double a = (p.k_t * p.M_s + p.b_h * p.b_t + p.M_m * (p.k_t + p.k_h)) / (2.0 * mm);
  const double printed = std::sqrt(a) - std::sqrt(a * a - p.k_h * p.k_t / mm);
  std::printf("  as printed: omega1 = %.1f\n", printed);
  EXPECT_LT(printed, 0.0);
  ContactModelParams broken = p;
  broken.M_s = -0.11;
  EXPECT_EQ(broken.validate().rfind("M_s: ", 0), 0u);
}

// L940–L946: closing the force loop with a gain K around eq. 4.4, "the root locus predicts that the
// instability frequency should occur at ω_crit = 1200 rad/sec"; the load cell's 130 Hz filter
// "causes a lower instability frequency". With the chosen masses (0.30 / 0.11 kg, which give
// ω1 = 41 rad/s above) the phase crossing is computed, and the closed loop's characteristic
// polynomial D + K N (times the filter's 1 + s/ω_f) is checked with Routh's array on either side
// of the critical gain.
TEST(ContactStability, TheForceLoopGoesUnstableNear1200RadPerSecond_L944) {
  const GimbalJoystickParams plant;
  ContactModelParams p;
  p.M_m = plant.M_m;
  p.M_s = plant.M_s;
  const ContactTransferFunction tf = contact_transfer_function(p);
  const double filter = 2.0 * kPi * 130.0;  // rad/s (L945)
  const CriticalForceGain bare = critical_force_gain(p);
  const CriticalForceGain filtered = critical_force_gain(p, filter);
  std::printf("  critical: %.1f rad/s at gain %.2f; with the 130 Hz filter %.1f rad/s at gain %.2f\n",
              bare.omega, bare.gain, filtered.omega, filtered.gain);
  EXPECT_NEAR(bare.omega, 1200.0, 60.0);  // the document's 1200 rad/s, to 5 %
  EXPECT_GT(bare.gain, 30.0);             // this model: 41–44
  EXPECT_LT(bare.gain, 60.0);
  EXPECT_LT(filtered.omega, 0.8 * bare.omega);  // the filter's lag lowers the crossing
  EXPECT_LT(filtered.gain, bare.gain);
  const auto closed_loop_stable = [&](double gain, double cutoff) {
    // (D (1 + s/ω_f) + K N), highest power first; without a filter, D + K N.
    std::vector<double> c;
    const std::vector<double> d(tf.denominator.begin(), tf.denominator.end());
    std::vector<double> n(d.size(), 0.0);
    for (std::size_t i = 0; i < tf.numerator.size(); ++i) n[d.size() - tf.numerator.size() + i] = tf.numerator[i];
    if (cutoff > 0.0) {
      c.assign(d.size() + 1, 0.0);
      for (std::size_t i = 0; i < d.size(); ++i) {
        c[i] += d[i] / cutoff;
        c[i + 1] += d[i] + gain * n[i];
      }
    } else {
      for (std::size_t i = 0; i < d.size(); ++i) c.push_back(d[i] + gain * n[i]);
    }
    return routh_hurwitz_stable(c);
  };
  EXPECT_TRUE(closed_loop_stable(0.98 * bare.gain, 0.0));
  EXPECT_FALSE(closed_loop_stable(1.02 * bare.gain, 0.0));
  EXPECT_TRUE(closed_loop_stable(0.98 * filtered.gain, filter));
  EXPECT_FALSE(closed_loop_stable(1.02 * filtered.gain, filter));
  // "The critical gain depends primarily on the transmission and contact stiffnesses" (L938): each
  // moves it (here a ten times stiffer cable lowers it to 32, as the transmission's damping b_t
  // counts for less), and a stiffer grip lowers it: "by stiffening the wrist … the instability is
  // excited" (L916).
  ContactModelParams stiffer_cable = p;
  stiffer_cable.k_t = 10.0 * p.k_t;
  ContactModelParams stiffer_grip = p;
  stiffer_grip.k_h = 2.0 * p.k_h;
  std::printf("  k_t x10: gain %.2f; k_h x2: gain %.2f\n", critical_force_gain(stiffer_cable).gain,
              critical_force_gain(stiffer_grip).gain);
  EXPECT_GT(std::abs(critical_force_gain(stiffer_cable).gain / bare.gain - 1.0), 0.1);
  EXPECT_LT(critical_force_gain(stiffer_grip).gain, 0.95 * bare.gain);
}

// Eq. 4.2: the servo of Fig. 4.4 (feed-forward through K_t*, proportional force feedback) driving
// the printed-disk motor (first-order, 8.8 ms, L378) through a transmission of true ratio K_t,
// sampled at 1 kHz, settles at F_des (K_t/K_t* + K_p K_t) / (1 + K_p K_t); the error left by a
// wrong K_t* shrinks as K_p grows.
TEST(ForceServo, SettlesAtEq4_2sStaticGain) {
  const double T = 1e-3, time_constant = 8.8e-3;
  const double a = std::exp(-T / time_constant);
  const double F_des = 5.0;  // N
  for (const double K_t : {0.7, 1.0, 1.3}) {  // true ratio, N per command unit; K_t* = 1
    double previous_error = 1e9;
    for (const double K_p : {0.0, 1.0, 4.0, 12.0}) {
      const ForceServoParams servo{1.0, K_p};
      double force = 0.0;  // the load cell's reading of the output
      for (int k = 0; k < 5000; ++k) {
        const double u = force_servo_command(servo, F_des, force);
        force = a * force + (1.0 - a) * K_t * u;  // the motor's lag, exactly held over T
      }
      const double expected = F_des * static_force_gain(servo, K_t);
      EXPECT_NEAR(force, expected, 1e-9 * F_des) << "K_t " << K_t << " K_p " << K_p;
      const double error = std::abs(force - F_des);
      if (K_t != 1.0) {
        EXPECT_LT(error, previous_error) << "K_t " << K_t << " K_p " << K_p;
        previous_error = error;
      } else {
        EXPECT_NEAR(error, 0.0, 1e-9);  // a right estimate needs no feedback
      }
    }
  }
  // Closed form against the document's expression, written out.
  const double K_t = 1.3, K_t_star = 1.1, K_p = 2.0;
  EXPECT_DOUBLE_EQ(static_force_gain({K_t_star, K_p}, K_t), (K_t / K_t_star + K_p * K_t) / (1.0 + K_p * K_t));
}

// Eqs. 3.29–3.34 against the cable's tensions written out: T1,2 = T_PL ∓ τ/2r at the pulley, the
// sleeve scales them (eqs. 3.30, 3.31), F_R is their difference (eq. 3.32).
TEST(CableDrive, CapstanAndSleeveFormulasFollowFromTheTensions_Eq3_29_to_3_34) {
  const double r = 0.009525, preload = 40.0;  // m (the drive pulley), N [I]
  for (const double mu_beta : {0.3, 1.0, 2.5}) {
    const double tau_max = capstan_slip_torque(r, preload, mu_beta);
    const auto ratio = [&](double tau) {  // T1 / T2 (eq. 3.29's left side)
      return (preload - tau / (2.0 * r)) / (preload + tau / (2.0 * r));
    };
    EXPECT_NEAR(ratio(tau_max), std::exp(-mu_beta), 1e-12) << mu_beta;  // slips exactly here
    EXPECT_GT(ratio(0.99 * tau_max), std::exp(-mu_beta)) << mu_beta;       // holds below
    EXPECT_LT(tau_max, 2.0 * r * preload);  // never more than the pre-load can carry
  }
  for (const double nu_alpha : {0.1, 0.5, 1.2}) {
    for (const double tau : {-0.3, 0.0, 0.2, 0.6}) {
      const double T1 = preload - tau / (2.0 * r), T2 = preload + tau / (2.0 * r);
      const double T1_out = T1 * std::exp(nu_alpha);  // eq. 3.30
      const double T2_out = T2 / std::exp(nu_alpha);  // eq. 3.31
      EXPECT_NEAR(sleeve_shaft_force(tau, r, preload, nu_alpha), T2_out - T1_out, 1e-9) << nu_alpha;
    }
    const double tau_c = sleeve_breakaway_torque(r, preload, nu_alpha);
    EXPECT_NEAR(sleeve_shaft_force(tau_c, r, preload, nu_alpha), 0.0, 1e-9);  // eq. 3.34
    const double printed_3_34 = (std::exp(nu_alpha) - std::exp(-nu_alpha)) /
                                (std::exp(-nu_alpha) + std::exp(nu_alpha)) * 2.0 * r * preload;
    EXPECT_NEAR(tau_c, printed_3_34, 1e-12);
    // Eq. 3.33's load factor with no pre-load: F_R / (τ/2r) = e^{−να} + e^{να}.
    EXPECT_NEAR(sleeve_shaft_force(0.4, r, 0.0, nu_alpha) / (0.4 / (2.0 * r)),
                std::exp(-nu_alpha) + std::exp(nu_alpha), 1e-12);
    // Eq. 3.37 as printed, T_PL (e^{−να} − e^{να}), is negative: the friction's magnitude is
    // 2 T_PL sinh(να), what F_R lacks at τ = 0.
    EXPECT_LT(preload * (std::exp(-nu_alpha) - std::exp(nu_alpha)), 0.0);
    EXPECT_NEAR(-sleeve_shaft_force(0.0, r, preload, nu_alpha), 2.0 * preload * std::sinh(nu_alpha), 1e-9);
  }
}

// ---------------------------------------------------------------------------------------------
// The hybrid rule, driven by q = A sin(ωt).

struct Motion {
  double q, q_dot, q_ddot;
};
Motion sine(double t, double A = 1.0, double w = 1.0) {
  return {A * std::sin(w * t), A * w * std::cos(w * t), -A * w * w * std::sin(w * t)};
}

enum class Element { kDamper, kSpring, kMass, kWall };
double element_torque(Element e, const Motion& m) {
  switch (e) {
    case Element::kDamper: return damper_torque(1.0, m.q_dot);
    case Element::kSpring: return spring_torque(1.0, m.q, 0.0);
    case Element::kMass: return mass_torque(1.0, m.q_ddot);
    case Element::kWall: return wall_torque(5.0, m.q, 0.5);
  }
  return 0.0;
}

// Eq. 4.6: the brake only ever takes power in, and motor plus brake give the element's torque.
TEST(HybridRule, BrakePowerIsNeverNegative_Eq4_6) {
  const HybridRuleParams rule{100.0, 1e-3};
  for (const Element e : {Element::kDamper, Element::kSpring, Element::kMass, Element::kWall}) {
    int braked = 0, samples = 0;
    double min_power = 0.0;
    for (int k = 0; k <= 20000; ++k) {
      const Motion m = sine(k * 1e-3);  // 20 s: three periods of ω = 1 rad/s
      const double tau = element_torque(e, m);
      // The user holds the element in balance: τ_u = −τ (pure element, no device inertia).
      const HybridSplit s = split_hybrid(tau, m.q_dot, -tau, rule);
      ASSERT_GE(s.brake, 0.0);
      if (std::abs(m.q_dot) >= rule.stick_velocity) {
        const double brake_on_joint = brake_joint_torque(s.brake, m.q_dot);
        EXPECT_NEAR(s.motor + brake_on_joint, tau, 1e-12);
        const double power_in = -brake_on_joint * m.q_dot;  // eq. 4.6's τ_b θ̇
        min_power = std::min(min_power, power_in);
        if (s.brake > 0.0) {
          ++braked;
          EXPECT_LE(tau * m.q_dot, 0.0);  // braked only while work is done on the element
          EXPECT_EQ(s.motor, 0.0);
        }
      }
      ++samples;
    }
    std::printf("  element %d: braked at %d of %d samples, min brake power %.3g W\n",
                static_cast<int>(e), braked, samples, min_power);
    EXPECT_GE(min_power, 0.0);
    EXPECT_GT(braked, 0);
  }
  // A wrong rule (brake whenever τ ≠ 0) fails the same check: the spring's unloading quarter.
  const Motion unloading = sine(2.0);  // q > 0, q̇ < 0: the spring pushes along the motion
  EXPECT_GT(spring_torque(1.0, unloading.q, 0.0) * unloading.q_dot, 0.0);
  EXPECT_EQ(split_hybrid(spring_torque(1.0, unloading.q, 0.0), unloading.q_dot, 0.0, rule).brake, 0.0);
}

// Fig. 4.10 (unit gains, sinusoidal motion): the damper's brake torque is a pure sinusoid in
// phase with the velocity; the spring's and the mass's brake torques exist only where power flows
// in (q q̇ > 0 for the spring, q̈ q̇ > 0 for the mass), half of each cycle, and jump where the
// power changes sign.
TEST(HybridRule, BrakeTorqueShapesOfFig4_10) {
  const HybridRuleParams rule{100.0, 1e-3};
  const int n = 40000;  // samples over 4 periods of ω = 1 rad/s
  const double step = 4.0 * 2.0 * kPi / n;
  double damper_err = 0.0;
  int spring_on = 0, mass_on = 0, spring_wrong = 0, mass_wrong = 0, motor_used_by_damper = 0;
  double spring_jump = 0.0;
  for (int k = 0; k < n; ++k) {
    const Motion m = sine(k * step);
    if (std::abs(m.q_dot) < rule.stick_velocity) continue;
    // Brake shaft torque as Fig. 4.10 plots it: the torque the shaft applies to the brake.
    const HybridSplit d = split_hybrid(damper_torque(1.0, m.q_dot), m.q_dot, 0.0, rule);
    damper_err = std::max(damper_err, std::abs(-brake_joint_torque(d.brake, m.q_dot) - m.q_dot));
    motor_used_by_damper += d.motor != 0.0;
    const HybridSplit s = split_hybrid(spring_torque(1.0, m.q, 0.0), m.q_dot, 0.0, rule);
    if (s.brake > 0.0) {
      ++spring_on;
      spring_wrong += !(m.q * m.q_dot > 0.0);
      EXPECT_NEAR(s.brake, std::abs(m.q), 1e-12);  // |K_b K_p θ| (eq. 4.8)
    }
    const HybridSplit a = split_hybrid(mass_torque(1.0, m.q_ddot), m.q_dot, 0.0, rule);
    if (a.brake > 0.0) {
      ++mass_on;
      mass_wrong += !(m.q_ddot * m.q_dot > 0.0);
      EXPECT_NEAR(a.brake, std::abs(m.q_ddot), 1e-12);  // |K_b K_a θ̈| (eq. 4.9)
    }
    // The spring's brake torque jumps from 0 to ≈ A at q = ±A, where q̇ changes sign.
    if (s.brake > 0.0) spring_jump = std::max(spring_jump, s.brake);
  }
  std::printf("  damper: max |tau_b - qdot| %.3g; spring braked %.3f of samples, mass %.3f; "
              "spring's largest brake torque %.4f (the jump at |q| = A)\n",
              damper_err, static_cast<double>(spring_on) / n, static_cast<double>(mass_on) / n,
              spring_jump);
  EXPECT_LT(damper_err, 1e-12);
  EXPECT_EQ(motor_used_by_damper, 0);
  EXPECT_EQ(spring_wrong, 0);
  EXPECT_EQ(mass_wrong, 0);
  EXPECT_NEAR(static_cast<double>(spring_on) / n, 0.5, 0.01);
  EXPECT_NEAR(static_cast<double>(mass_on) / n, 0.5, 0.01);
  EXPECT_GT(spring_jump, 0.999);
}

// L1011: the brake takes the energy in, the motor gives it back. Held at 1 kHz, the release
// follows the constitutive law a tick early and the brake a tick late, so the plain rule returns
// a little more than it absorbed; EnergyBoundedRelease never does. Energies per tick are exact
// for held commands: the brake b absorbs b |Δq|, the motor m delivers m Δq.
TEST(HybridRule, HybridSpringNeverReturnsMoreEnergyThanItAbsorbed_L1011) {
  const HybridRuleParams rule{100.0, 1e-3};
  const double K = 400.0, A = 0.3, w = 2.0 * kPi * 2.0, T = 1e-3;  // 2 Hz, 0.3 rad
  const double stored = 0.5 * K * A * A;
  const double tolerance = 1e-12 * stored;  // round-off only
  double worst_excess = -1e300;
  const auto run = [&](int cycles, double& absorbed, double& returned) {
    EnergyBoundedRelease release;
    absorbed = returned = 0.0;
    const int ticks = static_cast<int>(std::lround(cycles / 2.0 / T));
    for (int k = 0; k < ticks; ++k) {
      const Motion m = sine(k * T, A, w);
      const double next_q = sine((k + 1) * T, A, w).q;
      const double tau = spring_torque(K, m.q, 0.0);
      HybridSplit s = split_hybrid(tau, m.q_dot, -tau, rule);
      s = release.limit(s, m.q, m.q_dot, T);
      absorbed += s.brake * std::abs(next_q - m.q);
      returned += s.motor * (next_q - m.q);
      worst_excess = std::max(worst_excess, returned - absorbed);
      EXPECT_LE(returned, absorbed + tolerance) << "tick " << k;
    }
  };
  double absorbed = 0.0, returned = 0.0;
  run(5, absorbed, returned);
  std::printf("  bounded, 5 cycles: absorbed %.5f J, returned %.5f J (1/2 K A^2 per cycle %.4f J); "
              "largest running excess %.3g J\n",
              absorbed, returned, stored, worst_excess);
  EXPECT_GT(returned, 0.97 * 5 * stored);  // it still gives almost all of it back
  EXPECT_GT(absorbed, 0.97 * 5 * stored);
  // The plain rule over one cycle, for comparison (not asserted per tick).
  double plain_absorbed = 0.0, plain_returned = 0.0;
  {
    const int ticks = static_cast<int>(std::lround(1.0 / 2.0 / T));
    for (int k = 0; k < ticks; ++k) {
      const Motion m = sine(k * T, A, w);
      const double dq = sine((k + 1) * T, A, w).q - m.q;
      const double tau = spring_torque(K, m.q, 0.0);
      const HybridSplit s = split_hybrid(tau, m.q_dot, -tau, rule);
      plain_absorbed += s.brake * std::abs(dq);
      plain_returned += s.motor * dq;
    }
  }
  std::printf("  plain rule, 1 cycle: absorbed %.5f J, returned %.5f J (excess %.3g J)\n",
              plain_absorbed, plain_returned, plain_returned - plain_absorbed);
  EXPECT_GT(plain_returned, plain_absorbed);  // why the bound exists
}

// L1041: near rest the user's force decides — brake while pushing into the wall, nothing the
// instant the push reverses.
TEST(HybridRule, BrakeWallHoldsWhileThePushIsInAndReleasesWhenItReverses_L1041) {
  const HybridRuleParams rule{7.78, 1e-3};
  const double tau = wall_torque(1000.0, 0.001, 0.0);  // 1 mrad in: −1 N·m
  const HybridSplit in = split_hybrid(tau, 0.0, +2.0, rule);  // pushing in
  EXPECT_DOUBLE_EQ(in.brake, 1.0);
  EXPECT_DOUBLE_EQ(in.motor, 0.0);
  const HybridSplit out = split_hybrid(tau, 0.0, -0.5, rule);  // pulling away
  EXPECT_DOUBLE_EQ(out.brake, 0.0);
  EXPECT_DOUBLE_EQ(out.motor, tau);
  // Beyond the brake's capacity the motor takes the rest, still dissipatively.
  const HybridSplit hard = split_hybrid(-10.0, 0.5, 0.0, rule);
  EXPECT_DOUBLE_EQ(hard.brake, 7.78);
  EXPECT_NEAR(hard.motor + brake_joint_torque(hard.brake, 0.5), -10.0, 1e-12);
  EXPECT_LT(hard.motor * 0.5, 0.0);
  EXPECT_EQ((HybridRuleParams{0.0, 1e-3}).validate().rfind("brake_limit: ", 0), 0u);
}

// ---------------------------------------------------------------------------------------------
// The plant.

/// Time at which samples taken every dt from t = 0 first reach 1 − 1/e of `final`, interpolated.
double time_to_63_percent(const std::vector<double>& samples, double dt, double final) {
  const double target = (1.0 - std::exp(-1.0)) * final;
  for (std::size_t k = 1; k < samples.size(); ++k) {
    if (samples[k] >= target) {
      const double fraction = (target - samples[k - 1]) / (samples[k] - samples[k - 1]);
      return (static_cast<double>(k - 1) + fraction) * dt;
    }
  }
  return std::numeric_limits<double>::infinity();
}

TEST(GimbalJoystickPlant, MotorAndBrakeLagsReach63PercentAtTheirTimeConstants_L378_L381) {
  const GimbalJoystickParams p;
  GimbalJoystickPlant plant(p, {Integrator::kRk4, 10}, {0.0, 0.0, 0.24});
  JoystickActuatorCommand command;
  command.motor = {1.0, 1.0, 0.5};
  command.brake = {4.0, 4.0, 1.0};
  const double dt = 1e-4;
  // One sample per tick of every lagged quantity, from t = 0.
  std::array<std::vector<double>, 6> trace;
  for (int k = 0; k <= 600; ++k) {
    for (int i = 0; i < 3; ++i) {
      trace[i].push_back(plant.state()[js::kMotor + i]);
      trace[3 + i].push_back(plant.state()[js::kBrake + i]);
    }
    plant.step(command, dt);
  }
  for (int i = 0; i < 6; ++i) {
    const double final = i < 3 ? command.motor[i] : command.brake[i - 3];
    const double t63 = time_to_63_percent(trace[i], dt, final);
    std::printf("  %s %d: 63 %% at %.4f ms\n", i < 3 ? "motor" : "brake", i % 3, 1e3 * t63);
    EXPECT_NEAR(t63, i < 3 ? 8.8e-3 : 12e-3, 0.02e-3);
  }
  // Saturation: a command above the motor limit delivers the limit (±1.78 / ±0.883 N·m).
  GimbalJoystickPlant saturated(p, {Integrator::kRk4, 10}, {0.0, 0.0, 0.24});
  JoystickActuatorCommand big;
  big.motor = {5.0, -5.0, 5.0};
  for (int k = 0; k < 2000; ++k) saturated.step(big, 1e-3, [](const Vec3&, const Vec3& ) { return Vec3{}; });
  EXPECT_NEAR(saturated.state()[js::kMotor + 0], 1.78, 1e-6);
  EXPECT_NEAR(saturated.state()[js::kMotor + 1], -1.78, 1e-6);
  EXPECT_NEAR(saturated.state()[js::kMotor + 2], 0.883, 1e-6);
}

// The brake as a Coulomb element (L963, Fig. 4.8): at rest it holds the hand's torque up to its
// clamping torque plus the gimbal friction, and slips beyond it.
TEST(GimbalJoystickPlant, BrakeHoldsTheHandUpToItsCapacity_Fig4_8) {
  const GimbalJoystickParams p;
  const double R = 0.24, brake = 1.0;
  const double capacity = brake + p.gimbal_friction;  // N·m on θ
  for (const double F : {0.9 * capacity / R, 1.1 * capacity / R}) {
    GimbalJoystickPlant plant(p, {Integrator::kRk4, 10}, {0.0, 0.0, R});
    JoystickState x = plant.state();
    x[js::kBrake + 0] = brake;  // brake already at its commanded torque
    plant.set_state(x);
    JoystickActuatorCommand command;
    command.brake = {brake, 0.0, 0.0};
    for (int k = 0; k < 200; ++k) {
      plant.step(command, 1e-3, [&](const Vec3&, const Vec3&) { return Vec3{F, 0.0, 0.0}; });
    }
    const double theta = plant.state()[js::kTheta];
    std::printf("  F_x %.3f N (R F_x = %.3f N.m vs capacity %.3f): theta after 0.2 s %.3g rad\n", F,
                R * F, capacity, theta);
    if (R * F < capacity) {
      EXPECT_EQ(theta, 0.0);
    } else {
      EXPECT_GT(theta, 1e-3);
    }
  }
}

// Transmission statics: a held shaft motor torque τ against a hand spring stretches the cable by
// τ / (r k_t) (f_t = k_t (x_m − R), L935).
TEST(GimbalJoystickPlant, CableStretchesByForceOverKt_L935) {
  GimbalJoystickParams p;
  p.F_d = 0.0;  // no sleeve friction and no residual brake torque: the equilibrium is unique
  p.brake_residual_shaft = 0.0;
  const double R0 = 0.24;
  GimbalJoystickPlant plant(p, {Integrator::kRk4, 10}, {0.0, 0.0, R0});
  JoystickActuatorCommand command;
  command.motor = {0.0, 0.0, 0.5};  // N·m at the pulley: 52.5 N along the shaft
  const double k_hand = 2000.0;
  for (int k = 0; k < 3000; ++k) {
    plant.step(command, 1e-3, [&](const Vec3& p_WT, const Vec3& v_WT) {
      return -k_hand * (p_WT - Vec3{0.0, 0.0, R0}) - 20.0 * v_WT;
    });
  }
  const double force = 0.5 / p.r;
  const double stretch = plant.state()[js::kXm] - plant.state()[js::kR];
  std::printf("  F %.2f N: stretch %.4f mm (F/k_t %.4f mm); R moved %.3f mm (F/k_hand %.3f mm)\n",
              force, 1e3 * stretch, 1e3 * force / p.k_t, 1e3 * (plant.state()[js::kR] - R0),
              1e3 * force / k_hand);
  EXPECT_NEAR(stretch, force / p.k_t, 1e-3 * force / p.k_t);
  EXPECT_NEAR(plant.state()[js::kR] - R0, force / k_hand, 1e-3 * force / k_hand);
}

// L1930: with the motors at full torque the θ rate passes 8 rad/s; checked once per 1 kHz period,
// the watchdog trips in the period it is exceeded, the safe commands (motors zero, brakes at the
// limit) stop the joystick, and it stays tripped until rearmed.
TEST(JoystickWatchdog, TripsWithinOnePeriodAndLatches_L1930) {
  const GimbalJoystickParams p;
  GimbalJoystickPlant plant(p, {Integrator::kRk4, 10}, {-0.7, 0.0, 0.24});
  JoystickWatchdog watchdog;
  JoystickActuatorCommand command;
  command.motor = {p.motor_limit_gimbal, 0.0, 0.0};
  int tripped_at = -1;
  double rate_at_trip = 0.0, rate_before = 0.0;
  for (int k = 0; k < 500; ++k) {
    const double before = plant.state()[js::kThetaDot];
    plant.step(command, 1e-3);
    const Vec3 rates = plant.measured_joint_rates();
    if (watchdog.check(rates.x, rates.y, p.r * rates.z) && tripped_at < 0) {
      tripped_at = k;
      rate_at_trip = rates.x;
      rate_before = before;
      command.motor = {0.0, 0.0, 0.0};
      command.brake = {p.brake_limit_gimbal, p.brake_limit_gimbal, p.brake_limit_shaft};
    }
  }
  std::printf("  tripped at tick %d: theta rate %.3f rad/s (%.3f one period before)\n", tripped_at,
              rate_at_trip, rate_before);
  ASSERT_GE(tripped_at, 0);
  EXPECT_GT(rate_at_trip, 8.0);
  EXPECT_LE(rate_before, 8.0);  // within one period of the crossing
  EXPECT_EQ(plant.state()[js::kThetaDot], 0.0);  // the brakes stopped it
  EXPECT_TRUE(watchdog.check(0.0, 0.0, 0.0));    // latched at rest
  watchdog.rearm();
  EXPECT_FALSE(watchdog.check(0.0, 0.0, 0.0));
  EXPECT_TRUE(watchdog.check(0.0, 0.0, 0.72));   // the shaft's 0.7143 m/s
  watchdog.rearm();
  EXPECT_TRUE(watchdog.check(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0));
}

}  // namespace
}  // namespace haptic::engine
