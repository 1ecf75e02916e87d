// Madill 1998 §6.4's H∞ implicit force controller for the axial joint (eq. 6.19, L3565–L3590),
// checked against what the thesis says of it: the loop gain P C crosses over at about 41.7 rad/s,
// its phase comes close to −180° around 2 rad/s and peaks at the crossover (a phase margin of
// about 28°), the controller is stable and minimum-phase, and at DC it is the wall's stiffness,
// about 257 N·m/rad. And the ideal controller C* = P_d⁻¹ − P⁻¹ for the wall K_p = 400, K_d = 0
// has its zeros at −44.30 and 44.25 (L3579).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <complex>
#include <cstdio>
#include <numbers>

#include "engine/analysis/routh.hpp"

namespace haptic::engine {
namespace {

using Complex = std::complex<double>;
using Matrix3 = std::array<std::array<double, 3>, 3>;

constexpr double kPi = std::numbers::pi;
// Eq. 6.19 as printed.
constexpr Matrix3 kA{{{-54.5, 44.8, -45.1}, {-124.8, -92.1, 73.9}, {31.4, 13.4, -27.9}}};
constexpr std::array<double, 3> kB{-721.0, -3228.0, 907.0};
constexpr std::array<double, 3> kC{4.19, -22.0, 37.3};
// The axial joint's plant (eq. 6.5, Table 5.4): P(s) = 1 / (J s² + B s).
constexpr double kInertia = 0.204;  // kg·m²
constexpr double kDamping = 0.012;  // N·m·s/rad

Complex determinant(const std::array<std::array<Complex, 3>, 3>& m) {
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
         m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

/// C(s) = C_c (sI − A_c)⁻¹ B_c, by Cramer's rule. Unit: N·m/rad.
Complex controller(Complex s) {
  std::array<std::array<Complex, 3>, 3> m{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) m[i][j] = (i == j ? s : 0.0) - kA[i][j];
  }
  const Complex det = determinant(m);
  Complex out = 0.0;
  for (int k = 0; k < 3; ++k) {  // x_k = det(m with column k replaced by B) / det
    auto mk = m;
    for (int i = 0; i < 3; ++i) mk[i][k] = kB[i];
    out += kC[k] * determinant(mk) / det;
  }
  return out;
}

Complex plant(Complex s) { return 1.0 / (kInertia * s * s + kDamping * s); }
Complex loop(double omega) {
  const Complex s(0.0, omega);
  return plant(s) * controller(s);
}
/// The loop's phase in degrees, in (−360°, 0°]: P C lags (P alone lags by 90° to 180°).
double phase_deg(Complex z) {
  const double degrees = std::arg(z) * 180.0 / kPi;
  return degrees > 0.0 ? degrees - 360.0 : degrees;
}

TEST(ImplicitForceHinf, LoopCrossesOverAt41_7RadPerSecondWith28DegreesOfPhaseMargin_Eq6_19) {
  double lo = 1.0, hi = 1000.0;  // |P C| falls through 1 once in between
  ASSERT_GT(std::abs(loop(lo)), 1.0);
  ASSERT_LT(std::abs(loop(hi)), 1.0);
  while (hi - lo > 1e-9 * hi) {
    const double mid = std::sqrt(lo * hi);
    (std::abs(loop(mid)) > 1.0 ? lo : hi) = mid;
  }
  const double crossover = lo;
  const double margin = 180.0 + phase_deg(loop(crossover));
  std::printf("  crossover %.2f rad/s, phase margin %.1f deg, C(0) %.1f N*m/rad\n", crossover, margin,
              controller(0.0).real());
  EXPECT_NEAR(crossover, 41.7, 0.1);  // L3583: "approximately 41.7 rad/s"
  EXPECT_NEAR(margin, 28.0, 1.0);
  // "The phase ventures very close to −180° around 2 rad/s but … peaks at the cross-over".
  EXPECT_LT(180.0 + phase_deg(loop(2.0)), 2.0);
  for (const double omega : {10.0, 20.0, 30.0, 60.0, 100.0}) {
    EXPECT_LT(180.0 + phase_deg(loop(omega)), margin + 0.5) << omega;
  }
  // At DC the controller is a stiffness: C(0) = −C_c A_c⁻¹ B_c, real.
  EXPECT_NEAR(controller(0.0).real(), 257.0, 1.0);
  EXPECT_NEAR(controller(0.0).imag(), 0.0, 1e-9);
}

TEST(ImplicitForceHinf, ControllerIsStableAndMinimumPhase_L3589) {
  // det(sI − A) = s³ − tr A s² + (sum of principal 2×2 minors) s − det A.
  const Matrix3& a = kA;
  const double trace = a[0][0] + a[1][1] + a[2][2];
  const double minors = (a[0][0] * a[1][1] - a[0][1] * a[1][0]) + (a[0][0] * a[2][2] - a[0][2] * a[2][0]) +
                        (a[1][1] * a[2][2] - a[1][2] * a[2][1]);
  const double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                     a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                     a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  const double poles[] = {1.0, -trace, minors, -det};
  EXPECT_TRUE(routh_hurwitz_stable(poles));
  // The numerator N(s) = C(s) det(sI − A), at most quadratic (D_c = 0), from three points.
  const auto characteristic = [&](double s) { return ((s - trace) * s + minors) * s - det; };
  const double n_at_0 = (controller(0.0) * characteristic(0.0)).real();
  const double n_at_1 = (controller(1.0) * characteristic(1.0)).real();
  const double n_at_m1 = (controller(-1.0) * characteristic(-1.0)).real();
  const double zeros[] = {(n_at_1 + n_at_m1) / 2.0 - n_at_0, (n_at_1 - n_at_m1) / 2.0, n_at_0};
  EXPECT_TRUE(routh_hurwitz_stable(zeros)) << zeros[0] << " " << zeros[1] << " " << zeros[2];
  // The fitted numerator reproduces C elsewhere (it is the whole numerator).
  const Complex s(0.3, 17.0);
  const Complex fitted = (zeros[0] * s * s + zeros[1] * s + zeros[2]) /
                         (((s - trace) * s + minors) * s - det);
  EXPECT_LT(std::abs(fitted - controller(s)), 1e-9 * std::abs(controller(s)));
}

// C* = P_d⁻¹ − P⁻¹ with P_d = 1 / (K_d s + K_p) (L3397–L3401): its zeros solve
// −J s² + (K_d − B) s + K_p = 0. With K_p = 400 N·m/rad, K_d = 0 they are the thesis' −44.30 and
// 44.25 (non-minimum phase, L3579).
TEST(ImplicitForceHinf, IdealControllersZerosAreMinus44_30And44_25) {
  const double K_p = 400.0, K_d = 0.0;
  const double a = -kInertia, b = K_d - kDamping, c = K_p;
  const double root = std::sqrt(b * b - 4.0 * a * c);
  const double z1 = (-b + root) / (2.0 * a), z2 = (-b - root) / (2.0 * a);
  // −44.310 and 44.251 here: the thesis' two decimals, the first off by one in the last.
  EXPECT_NEAR(std::min(z1, z2), -44.30, 0.015);
  EXPECT_NEAR(std::max(z1, z2), 44.25, 0.005);
}

}  // namespace
}  // namespace haptic::engine
