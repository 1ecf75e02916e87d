// Contact impedances: the three discretizations against the continuous law (000 eqs. 8.9–8.17),
// Colgate's bound (Madill eq. 2.6), the sampled wall margin against a time-domain simulation,
// the virtual coupling and the tangent-plane model (Russo ch. 5).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <vector>

#include "engine/control/dc_motor_control.hpp"
#include "engine/device/exact_step.hpp"
#include "engine/device/point_mass_plant.hpp"
#include "engine/scene/impedance.hpp"
#include "support/allocation_counter.hpp"

namespace haptic::engine {
namespace {

using D = ImpedanceDiscretization;

// --- Weights ----------------------------------------------------------------------------------

TEST(Impedance, ExactWeightsSumToTheStiffness_000Eq8_12) {
  for (const double K : {10.0, 1000.0, 2e4}) {
    for (const double B : {0.01, 1.0, 5.0}) {
      for (const double T : {1e-4, 1e-3, 1e-2}) {
        const ImpedanceWeights w = impedance_weights({K, B, 0.0}, D::kExactZoh, T);
        EXPECT_NEAR(w.lag[0] + w.lag[1], K, 1e-12 * w.lag[0]) << K << " " << B << " " << T;
        // The same weights as the torsion spring's (the form is reused, not copied).
        const SpringDamperCoefficients c = exact_delayed_coefficients(K, B, T);
        EXPECT_EQ(w.lag[0], c.c1);
        EXPECT_EQ(w.lag[1], c.c2);
        EXPECT_EQ(w.lag[2], 0.0);
        EXPECT_EQ(w.velocity_gain, 0.0);
      }
    }
  }
  // eq. 8.12a as printed: a1 = K e^x / (e^x − 1), x = KT/B.
  const double x = 1000.0 * 1e-3 / 1.0;
  EXPECT_NEAR(impedance_weights({1000.0, 1.0, 0.0}, D::kExactZoh, 1e-3).lag[0],
              1000.0 * std::exp(x) / (std::exp(x) - 1.0), 1e-9);
}

TEST(Impedance, ExactWeightsTendToTheBackwardOnesAtTheirLimits_000Eq8_17) {
  const double T = 1e-3;
  // B → 0: the pure spring, a1 → K, a2 → 0; exactly the backward weights at B = 0.
  const ImpedanceWeights stiff = impedance_weights({1000.0, 1e-9, 0.0}, D::kExactZoh, T);
  EXPECT_NEAR(stiff.lag[0], 1000.0, 1e-9);
  EXPECT_NEAR(stiff.lag[1], 0.0, 1e-9);
  const ImpedanceWeights spring = impedance_weights({1000.0, 0.0, 0.0}, D::kExactZoh, T);
  EXPECT_EQ(spring.lag[0], 1000.0);
  EXPECT_EQ(spring.lag[1], 0.0);
  // K → 0: the pure damper, a1 = −a2 → B/T.
  const ImpedanceWeights soft = impedance_weights({1e-9, 2.0, 0.0}, D::kExactZoh, T);
  EXPECT_NEAR(soft.lag[0], 2000.0, 1e-6);
  EXPECT_NEAR(soft.lag[1], -2000.0, 1e-6);
  // And small T: a_i → b_i to first order in KT/B (eq. 8.17).
  const ImpedanceWeights a = impedance_weights({100.0, 1.0, 0.0}, D::kExactZoh, 1e-5);
  const ImpedanceWeights b = impedance_weights({100.0, 1.0, 0.0}, D::kBackwardDifference, 1e-5);
  EXPECT_NEAR(a.lag[0] / b.lag[0], 1.0, 1e-3);
}

TEST(Impedance, ValidationNamesTheFieldAndValue) {
  EXPECT_EQ(validate_impedance({1000.0, 1.0, 0.0}, 1e-3), "");
  EXPECT_EQ(validate_impedance({NAN, 1.0, 0.0}, 1e-3),
            "stiffness: must be finite and >= 0, got nan");
  EXPECT_EQ(validate_impedance({1.0, -1.0, 0.0}, 1e-3), "damping: must be finite and >= 0, got -1");
  EXPECT_EQ(validate_impedance({1.0, 1.0, INFINITY}, 1e-3), "mass: must be finite and >= 0, got inf");
  EXPECT_EQ(validate_impedance({1.0, 1.0, 0.0}, 0.0), "period: must be finite and > 0, got 0");
}

// --- Against the continuous law ---------------------------------------------------------------

/// The continuous spring-damper K d + B ḋ = f(t) under a force held over each period, integrated
/// with RK4 at T/1000 (independent of 000 eq. 8.8); the exact ZOH filter fed its samples must
/// give back, at every sample k, the force held over [(k−1)T, kT) (000 eq. 8.9 shifted).
TEST(Impedance, ExactZohRecoversTheHeldForceAtTheSamples_000Eq8_9) {
  const double K = 1000.0, B = 2.0, T = 1e-3;
  const auto held_force = [](int k) { return 1.0 + 0.5 * std::sin(0.3 * k) + (k > 40 ? 2.0 : 0.0); };
  ImpedanceFilter exact({K, B, 0.0}, D::kExactZoh, T);
  ImpedanceFilter backward({K, B, 0.0}, D::kBackwardDifference, T);
  exact.reset(0.0);  // 000 eq. 8.11's initial condition: d(k0) = 0
  backward.reset(0.0);
  double d = 0.0;
  double worst_exact = 0.0, worst_backward = 0.0;
  for (int k = 1; k <= 200; ++k) {
    const double f = held_force(k - 1);
    const int n = 1000;
    const double h = T / n;
    const auto rate = [&](double x) { return (f - K * x) / B; };
    for (int i = 0; i < n; ++i) {
      const double k1 = rate(d), k2 = rate(d + 0.5 * h * k1), k3 = rate(d + 0.5 * h * k2),
                   k4 = rate(d + h * k3);
      d += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    }
    worst_exact = std::max(worst_exact, std::abs(exact.update(d) - f));
    worst_backward = std::max(worst_backward, std::abs(backward.update(d) - f));
  }
  EXPECT_LT(worst_exact, 1e-9);     // exact to the integration's round-off
  EXPECT_GT(worst_backward, 0.1);   // the backward difference is not: O(T) lag
}

/// Step response of M d̈ + B ḋ + K d = F0 (underdamped), written out for all t; the continuous law
/// gives f(t) = F0 at every t. Largest |f(k) − F0| over 0 < t <= 0.2 s for one discretization,
/// the filter started from the exact state at t = −4T and warmed up to t = 0.
double step_response_error(D discretization, double T) {
  const double M = 0.05, B = 2.0, K = 1000.0, F0 = 1.0;
  const double wn2 = K / M, sigma = B / (2.0 * M), wd = std::sqrt(wn2 - sigma * sigma);
  const auto d = [&](double t) {
    return F0 / K * (1.0 - std::exp(-sigma * t) * (std::cos(wd * t) + sigma / wd * std::sin(wd * t)));
  };
  const auto ddot = [&](double t) { return F0 / K * wn2 / wd * std::exp(-sigma * t) * std::sin(wd * t); };
  const auto dddot = [&](double t) {
    return F0 / K * wn2 / wd * std::exp(-sigma * t) * (wd * std::cos(wd * t) - sigma * std::sin(wd * t));
  };
  ImpedanceFilter filter({K, B, M}, discretization, T);
  const int start = -4;
  filter.reset(d(start * T), ddot(start * T), dddot(start * T));
  double worst = 0.0;
  const int ticks = static_cast<int>(std::lround(0.2 / T));
  for (int k = start + 1; k <= ticks; ++k) {
    const double f = filter.update(d(k * T));
    if (k >= 1) worst = std::max(worst, std::abs(f - F0));
  }
  return worst;
}

TEST(Impedance, StepResponseErrorIsFirstOrderBackwardAndSecondOrderTustin) {
  for (const D discretization : {D::kBackwardDifference, D::kTustin}) {
    const double e1 = step_response_error(discretization, 1e-3);
    const double e2 = step_response_error(discretization, 5e-4);
    const double e3 = step_response_error(discretization, 2.5e-4);
    const double order12 = std::log2(e1 / e2), order23 = std::log2(e2 / e3);
    const double expected = discretization == D::kTustin ? 2.0 : 1.0;
    EXPECT_NEAR(order12, expected, 0.15) << static_cast<int>(discretization) << " " << e1 << " " << e2;
    EXPECT_NEAR(order23, expected, 0.1) << static_cast<int>(discretization) << " " << e2 << " " << e3;
  }
  // The mass term's second-order formula has a large constant (11/12 T² M d⁗): at 1 kHz Tustin
  // is no better than the backward difference on this fast (22 Hz) response, at 4 kHz it is.
  EXPECT_LT(2.0 * step_response_error(D::kTustin, 2.5e-4),
            step_response_error(D::kBackwardDifference, 2.5e-4));
}

TEST(Impedance, ResetSeedsTheHistorySoARampGivesItsExactForce) {
  // d = d0 + r t (m, m/s): K d + B r for every form once reset with the ramp's own rate.
  const double K = 500.0, B = 3.0, M = 0.02, T = 1e-3, r = 0.01;
  for (const D discretization : {D::kBackwardDifference, D::kTustin}) {
    ImpedanceFilter filter({K, B, M}, discretization, T);
    filter.reset(0.0, r, 0.0);
    for (int k = 1; k <= 5; ++k) {
      EXPECT_NEAR(filter.update(r * k * T), K * r * k * T + B * r, 1e-12) << k;
    }
  }
  // Default-constructed: no force, no state.
  ImpedanceFilter none;
  EXPECT_EQ(none.update(1.0), 0.0);
}

TEST(Impedance, UpdateAllocatesNothing) {
  ImpedanceFilter filter({1000.0, 1.0, 0.01}, D::kTustin, 1e-3);
  VirtualCoupling coupling({40.0, 0.01}, 1e-3);
  TangentPlane plane;
  plane.normal = {1000.0, 1.0, 0.0};
  plane.tangential_stiffness = 100.0;
  TangentPlaneContact contact(D::kExactZoh, 1e-3);
  contact.set_plane(plane);
  double sum = 0.0;
  haptic::test::reset_allocations();
  {
    haptic::test::CountAllocations counting;
    for (int k = 0; k < 1000; ++k) {
      const double z = 0.001 * std::sin(0.01 * k);
      sum += filter.update(z);
      sum += coupling.force({0, 0, z}, {}).z;
      sum += contact.update({0.001, 0, z}, {0, 0, 0.01}).F_T_W.z;
    }
  }
  EXPECT_EQ(haptic::test::allocations(), 0u);
  EXPECT_TRUE(std::isfinite(sum));
}

// --- Colgate's bound and the sampled margin ---------------------------------------------------

TEST(Impedance, ColgateBoundNumbers_MadillEq2_6) {
  EXPECT_DOUBLE_EQ(colgate_bound(1000.0, 1.0, 1e-3), 1.5);
  EXPECT_DOUBLE_EQ(colgate_bound(1000.0, -1.0, 1e-3), 1.5);  // |B|
  // Madill: b = 0.0115 N·s/m at T = 1 ms allows K < 23 N/m.
  EXPECT_NEAR(colgate_bound(23.0, 0.0, 1e-3), 0.0115, 1e-15);
  // Document 001's device (b = 0.022) at 1 kHz: a pure spring is passive below 44 N/m.
  EXPECT_NEAR(colgate_bound(44.0, 0.0, 1e-3), 0.022, 1e-15);
  EXPECT_DOUBLE_EQ(colgate_bound(0.0, 0.5, 1e-3), 0.5);
}

TEST(Impedance, RootsAndJuryAgreeOnKnownPolynomials) {
  // (z − 0.5)(z + 0.9)(z² − 1.2 z + 0.72): roots 0.5, −0.9, 0.6 ± 0.6i (|z| = 0.8485).
  Polynomial p;
  p.degree = 4;
  // Expanded: z⁴ − 0.8 z³ − 0.21 z² + 0.828 z − 0.324.
  p.c = {-0.324, 0.828, -0.21, -0.8, 1.0};
  const auto roots = polynomial_roots(p);
  double largest = 0.0;
  for (int i = 0; i < 4; ++i) {
    const std::complex<double> r = roots[static_cast<std::size_t>(i)];
    largest = std::max(largest, std::abs(r));
    const double distance = std::min({std::abs(r - 0.5), std::abs(r + 0.9),
                                      std::abs(r - std::complex<double>(0.6, 0.6)),
                                      std::abs(r - std::complex<double>(0.6, -0.6))});
    EXPECT_LT(distance, 1e-12) << r;
  }
  EXPECT_NEAR(largest, 0.9, 1e-12);
  EXPECT_TRUE(schur_stable(p));
  Polynomial q;
  q.degree = 2;
  q.c = {0.81, -1.8, 1.0};  // (z − 0.9)²
  EXPECT_TRUE(schur_stable(q));
  q.c = {1.0201, -2.02, 1.0};  // (z − 1.01)²
  EXPECT_FALSE(schur_stable(q));
  q.c = {1.0, 0.0, 1.0};  // z² + 1: on the circle
  EXPECT_FALSE(schur_stable(q));
}

const MassDamperDevice kDevice001{0.01, 0.022};  // document 001's device

/// For a pure spring behind the backward difference the loop is D(z) + K N(z) (second order) and
/// its limit is where the constant coefficient reaches 1: K' = (1 − e) m / (T² (φ² − e g)),
/// ≈ 2b/T for bT/m ≪ 1 (Gillespie & Cutkosky 1996).
TEST(Impedance, SampledMarginOfASpringMatchesTheClosedForm) {
  const double T = 1e-3, m = kDevice001.mass, b = kDevice001.damping;
  const double x = b * T / m, e = std::exp(-x), phi = (1.0 - e) / x, g = (x - 1.0 + e) / (x * x);
  const double closed_form = (1.0 - e) * m / (T * T * (phi * phi - e * g));
  const SampledWallMargin margin =
      sampled_wall_margin({30.0, 0.0, 0.0}, D::kBackwardDifference, kDevice001, T);
  EXPECT_NEAR(margin.max_stable_stiffness / closed_form, 1.0, 1e-7);
  EXPECT_NEAR(margin.max_stable_stiffness, 44.016, 1e-3);  // 2b/T = 44, and a little more
  EXPECT_TRUE(margin.stable);
  EXPECT_TRUE(margin.passive);  // 30 T/2 = 0.015 < 0.022
  EXPECT_LT(margin.max_pole_magnitude, 1.0);
  // The exact form with B = 0 is the same law.
  EXPECT_EQ(sampled_wall_margin({30.0, 0.0, 0.0}, D::kExactZoh, kDevice001, T).max_stable_stiffness,
            margin.max_stable_stiffness);
}

TEST(Impedance, AFractionalDelayLiesBetweenItsWholeTicksAndMeetsThemAtTheEnds) {
  // An identified delay is fractional (docs/identification.md): Thiran's all-pass carries it, so
  // the stiffness limit falls monotonically from 1 tick to 2 and equals theirs at the ends.
  const double T = 1e-3;
  const ImpedanceParams wall{100.0, 0.1, 0.0};
  double previous = sampled_wall_margin(wall, D::kBackwardDifference, kDevice001, T, 1.0).max_stable_stiffness;
  const double two = sampled_wall_margin(wall, D::kBackwardDifference, kDevice001, T, 2.0).max_stable_stiffness;
  EXPECT_EQ(previous, sampled_wall_margin(wall, D::kBackwardDifference, kDevice001, T, 1u).max_stable_stiffness);
  for (const double d : {1.25, 1.5, 1.75, 1.999999}) {
    const double k = sampled_wall_margin(wall, D::kBackwardDifference, kDevice001, T, d).max_stable_stiffness;
    EXPECT_LT(k, previous) << d;
    EXPECT_GT(k, two * (1.0 - 1e-4)) << d;
    previous = k;
  }
  EXPECT_NEAR(previous / two, 1.0, 1e-3);
}

/// Simulates the wall (linear: it may pull, as in the analysis) on the device with the project's
/// exact ZOH plant, from 1 mm penetration at rest (the filter told the rate rate_previous);
/// returns the peak |d| of each 500-tick window.
std::vector<double> simulate_wall(const ImpedanceParams& wall, D discretization, double T,
                                  int ticks, double rate_previous = 0.0) {
  PointMassParams params;
  params.mass = kDevice001.mass;
  params.damping = kDevice001.damping;
  params.substeps = 1;  // exact for a held force
  params.workspace_min = {-1e9, -1e9, -1e9};
  params.workspace_max = {1e9, 1e9, 1e9};
  PointMassPlant plant(params, {{-1e-3, 0, 0}, {}});  // wall x < 0, normal +x: d = −x
  ImpedanceFilter filter(wall, discretization, T);
  filter.reset(1e-3, rate_previous);
  std::vector<double> peaks(static_cast<std::size_t>(ticks / 500), 0.0);
  const auto none = [](const Vec3&, const Vec3&) { return Vec3{}; };
  for (int k = 0; k < ticks; ++k) {
    const double d = -plant.state().p_WT.x;
    auto& peak = peaks[static_cast<std::size_t>(std::min<int>(k / 500, static_cast<int>(peaks.size()) - 1))];
    peak = std::max(peak, std::abs(d));
    plant.step({filter.update(d), 0, 0}, T, none);
  }
  return peaks;
}

/// Peak of the last window over the peak of the first.
double simulated_growth(const ImpedanceParams& wall, D discretization, double T, int ticks) {
  const std::vector<double> peaks = simulate_wall(wall, discretization, T, ticks);
  return peaks.back() / peaks.front();
}

/// Growth per tick between window `from` and the last window.
double growth_per_tick(const std::vector<double>& peaks, std::size_t from) {
  return std::pow(peaks.back() / peaks[from], 1.0 / (500.0 * static_cast<double>(peaks.size() - 1 - from)));
}

TEST(Impedance, SampledMarginMatchesTimeDomainSimulation_Device001) {
  const double T = 1e-3;
  struct Case {
    ImpedanceParams wall;
    D discretization;
  };
  for (const Case& c : {Case{{30.0, 0.0, 0.0}, D::kBackwardDifference},
                        Case{{30.0, 0.005, 0.0}, D::kExactZoh},
                        Case{{30.0, 0.5, 0.0}, D::kExactZoh},
                        Case{{30.0, 0.5, 0.0}, D::kBackwardDifference},
                        Case{{30.0, 0.0, 0.0}, D::kTustin}}) {
    const SampledWallMargin margin = sampled_wall_margin(c.wall, c.discretization, kDevice001, T);
    ASSERT_GT(margin.max_stable_stiffness, 0.0);
    ASSERT_TRUE(std::isfinite(margin.max_stable_stiffness));
    ImpedanceParams below = c.wall, above = c.wall;
    below.stiffness = 0.98 * margin.max_stable_stiffness;
    above.stiffness = 1.02 * margin.max_stable_stiffness;
    const int ticks = 60000;
    EXPECT_LT(simulated_growth(below, c.discretization, T, ticks), 0.5)
        << static_cast<int>(c.discretization) << " K' = " << margin.max_stable_stiffness;
    EXPECT_GT(simulated_growth(above, c.discretization, T, ticks), 2.0)
        << static_cast<int>(c.discretization) << " K' = " << margin.max_stable_stiffness;
    // The reported pole magnitude is the simulated growth per tick.
    ImpedanceParams far = c.wall;
    far.stiffness = 1.5 * margin.max_stable_stiffness;
    const double r = sampled_wall_margin(far, c.discretization, kDevice001, T).max_pole_magnitude;
    const double per_tick = growth_per_tick(simulate_wall(far, c.discretization, T, 2000), 1);
    EXPECT_NEAR(per_tick, r, 2e-4 * r) << static_cast<int>(c.discretization);
  }
}

/// A wall on a device whose force lags its command by τ_a (the force f follows the held command
/// F through ḟ = (F − f)/τ_a, the mass-damper under f): 200 sub-steps a tick, f's step exact and
/// the mass-damper's exact under f held over each; from 1 mm penetration at rest. Peak |d| of the
/// first and the last 500-tick window, their ratio.
double lagged_wall_growth(const ImpedanceParams& wall, const MassDamperDevice& device, double T, int ticks) {
  ImpedanceFilter filter(wall, D::kBackwardDifference, T);
  filter.reset(1e-3, 0.0);
  double x = -1e-3, v = 0.0, f = 0.0;
  double first = 0.0, last = 0.0;
  const int substeps = 200;
  const double h = T / substeps;
  const ExactMassDamperStep step = ExactMassDamperStep::of(device.mass, device.damping, h);
  for (int k = 0; k < ticks; ++k) {
    const double d = -x;
    if (k < 500) first = std::max(first, std::abs(d));
    if (k >= ticks - 500) last = std::max(last, std::abs(d));
    const double command = filter.update(d);
    for (int s = 0; s < substeps; ++s) {
      f = command + (f - command) * std::exp(-h / device.actuator_lag);
      step.advance(x, v, f / device.mass);
    }
  }
  return last / first;
}

TEST(Impedance, AnActuatorsLagIsSampledExactlyAndItsMarginMatchesTheSimulation) {
  // 004's motor time constant on a light device: the lag takes most of the margin a damper gives.
  const double T = 1e-3;
  const MassDamperDevice lagged{0.05, 0.5, 8.8e-3};
  const ImpedanceParams wall{100.0, 1.0, 0.0};
  const double k_lag = sampled_wall_margin(wall, D::kBackwardDifference, lagged, T).max_stable_stiffness;
  const double k_none =
      sampled_wall_margin(wall, D::kBackwardDifference, {lagged.mass, lagged.damping}, T).max_stable_stiffness;
  ASSERT_TRUE(std::isfinite(k_lag) && k_lag > 0.0);
  EXPECT_LT(k_lag, 0.5 * k_none) << "a lag costs margin";
  ImpedanceParams below = wall, above = wall;
  below.stiffness = 0.97 * k_lag;
  above.stiffness = 1.03 * k_lag;
  EXPECT_LT(lagged_wall_growth(below, lagged, T, 20000), 0.8) << "K' = " << k_lag;
  EXPECT_GT(lagged_wall_growth(above, lagged, T, 20000), 1.25) << "K' = " << k_lag;
  // A vanishing lag is the device without one.
  const double k_tiny =
      sampled_wall_margin(wall, D::kBackwardDifference, {lagged.mass, lagged.damping, 1e-8}, T).max_stable_stiffness;
  EXPECT_NEAR(k_tiny, k_none, 1e-3 * k_none);
}

/// The bilinear damper has its pole at z = −1; in the loop the device's ZOH pushes it just
/// outside the unit circle for every B > 0, whatever K: the margin reports no stable K', and the
/// simulation grows at the reported rate, alternating sign every tick (the Nyquist frequency).
TEST(Impedance, TustinDamperRingsUnstablyAtNyquistOnTheDevice) {
  const double T = 1e-3;
  const ImpedanceParams wall{30.0, 5.0, 0.0};
  const SampledWallMargin margin = sampled_wall_margin(wall, D::kTustin, kDevice001, T);
  EXPECT_FALSE(margin.stable);
  EXPECT_EQ(margin.max_stable_stiffness, 0.0);
  EXPECT_NEAR(margin.max_pole_magnitude, 1.000244, 1e-6);
  // The backward and exact forms of the same wall are stable.
  EXPECT_TRUE(sampled_wall_margin(wall, D::kBackwardDifference, kDevice001, T).stable);
  EXPECT_TRUE(sampled_wall_margin(wall, D::kExactZoh, kDevice001, T).stable);
  // Started with a Tustin velocity state 10 mm/s off (the tool is at rest): the slow modes have
  // decayed by 10 s, and from there the Nyquist ripple grows at the reported rate.
  const std::vector<double> peaks = simulate_wall(wall, D::kTustin, T, 30000, 1e-2);
  EXPECT_NEAR(growth_per_tick(peaks, 20), margin.max_pole_magnitude, 2e-6);
  EXPECT_GT(peaks.back(), 50.0 * peaks[20]);
}

// --- Virtual coupling -------------------------------------------------------------------------

TEST(Impedance, VirtualCouplingDesignIsPassiveForDevice001) {
  const VirtualCouplingDesign design = design_virtual_coupling(0.01, 0.022, 1e-3);
  EXPECT_DOUBLE_EQ(design.gains.damping, 0.011);
  EXPECT_NEAR(design.gains.stiffness, 19.8, 1e-12);  // 0.9 · 2 (0.022 − 0.011) / 1e-3
  EXPECT_LT(colgate_bound(design.gains.stiffness, design.gains.damping, 1e-3), 0.022);
  EXPECT_NEAR(design.natural_frequency, std::sqrt(1980.0), 1e-9);
  // Passive ⇒ the coupling as a wall on the device is stable with room.
  const SampledWallMargin margin = sampled_wall_margin(
      {design.gains.stiffness, design.gains.damping, 0.0}, D::kBackwardDifference, kDevice001, 1e-3);
  EXPECT_TRUE(margin.stable);
  EXPECT_GT(margin.max_stable_stiffness, design.gains.stiffness);
  // No damping, no passive coupling.
  EXPECT_EQ(design_virtual_coupling(0.01, 0.0, 1e-3).gains.stiffness, 0.0);
}

TEST(Impedance, VirtualCouplingPullsTheToolTowardsTheProxyWithBackwardDamping) {
  VirtualCoupling coupling({100.0, 0.5}, 1e-3);
  coupling.reset();
  // Proxy 2 mm ahead in x: spring 0.2 N plus the damper on the jump of e (2 mm in one tick).
  const Vec3 F = coupling.force({0, 0, 0}, {0.002, 0, 0});
  EXPECT_NEAR(F.x, 100.0 * 0.002 + 0.5 * 0.002 / 1e-3, 1e-12);
  EXPECT_EQ(F.y, 0.0);
  // Held still: the spring alone.
  EXPECT_NEAR(coupling.force({0, 0, 0}, {0.002, 0, 0}).x, 0.2, 1e-12);
}

// --- Tangent plane ----------------------------------------------------------------------------

TangentPlane floor_plane() {
  TangentPlane plane;
  plane.point_W = {0, 0, 0};
  plane.normal_W = {0, 0, 1};
  plane.reference_W = {0, 0, 0};
  plane.normal = {2000.0, 5.0, 0.0};
  plane.tangential_stiffness = 200.0;
  plane.tangential_damping = 2.0;
  return plane;
}

TEST(Impedance, TangentPlanePushesOnlyOutward_RussoCh5) {
  TangentPlaneContact contact(D::kBackwardDifference, 1e-3);
  EXPECT_EQ(contact.update({0, 0, -0.001}, {}).F_T_W, Vec3{});  // no plane yet
  contact.set_plane(floor_plane());
  // Above the plane: nothing.
  TangentPlaneForce f = contact.update({0.01, 0, 0.002}, {0, 0, -0.5});
  EXPECT_FALSE(f.in_contact);
  EXPECT_EQ(f.F_T_W, Vec3{});
  // Into the plane and back out fast: the raw law K d + B ḋ turns negative on the way out, the
  // normal force never does.
  double z = 0.0;
  bool clamped = false;
  for (int k = 0; k < 40; ++k) {
    const double vz = k < 20 ? -0.1 : 0.4;
    z += vz * 1e-3;
    f = contact.update({0, 0, z}, {0, 0, vz});
    EXPECT_GE(f.F_T_W.z, 0.0) << k;
    if (f.in_contact && vz > 0 && f.F_T_W.z == 0.0) clamped = true;
    EXPECT_EQ(f.in_contact, z < 0.0) << k;
  }
  EXPECT_TRUE(clamped);
  // Deep and still: K_n d along +n.
  contact.reset();
  contact.update({0, 0, -0.001}, {});
  f = contact.update({0, 0, -0.001}, {});
  EXPECT_NEAR(f.F_T_W.z, 2.0, 1e-12);
  EXPECT_NEAR(f.penetration, 0.001, 1e-15);
}

TEST(Impedance, TangentPlaneTangentialSpringReturnsToTheReferencePoint) {
  // The default device pressed onto a tilted plane by a 1 N push, released 5 mm from the
  // reference point along the surface.
  TangentPlane plane = floor_plane();
  const double s = std::sqrt(0.5);
  plane.normal_W = {0, s, s};
  plane.reference_W = {0.002, -0.001, 0.001};  // on the plane
  TangentPlaneContact contact(D::kExactZoh, 1e-3);
  contact.set_plane(plane);
  PointMassParams params;
  params.substeps = 10;
  const Vec3 start = plane.reference_W + Vec3{0.005, 0, 0};
  PointMassPlant plant(params, {start, {}});
  const Vec3 push = -1.0 * plane.normal_W;
  const auto hand = [&](const Vec3&, const Vec3&) { return push; };
  for (int k = 0; k < 3000; ++k) {
    const TangentPlaneForce f = contact.update(plant.state().p_WT, plant.state().v_WT);
    plant.step(f.F_T_W, 1e-3, hand);
  }
  const Vec3 e = plant.state().p_WT - plane.reference_W;
  const Vec3 e_t = e - dot(e, plane.normal_W) * plane.normal_W;
  EXPECT_LT(norm(e_t), 1e-6);                                  // back at the reference point
  EXPECT_NEAR(-dot(e, plane.normal_W), 1.0 / 2000.0, 1e-7);    // resting at F / K_n
}

TEST(Impedance, TangentPlaneUpdateDuringContactDoesNotSpikeTheDamper) {
  TangentPlane plane = floor_plane();
  plane.tangential_stiffness = 0.0;
  plane.tangential_damping = 0.0;
  TangentPlaneContact contact(D::kBackwardDifference, 1e-3);
  contact.set_plane(plane);
  contact.update({0, 0, -0.001}, {});
  EXPECT_NEAR(contact.update({0, 0, -0.001}, {}).F_T_W.z, 2.0, 1e-12);
  // The client moves the plane up by 0.1 mm: the spring sees 0.1 mm more, the damper nothing
  // (a raw history would add B · 0.1 mm / T = 0.5 N).
  plane.point_W.z = 0.0001;
  contact.set_plane(plane);
  EXPECT_NEAR(contact.update({0, 0, -0.001}, {}).F_T_W.z, 2.2, 1e-12);
}

TEST(Impedance, TangentPlaneValidationNamesTheField) {
  TangentPlane plane = floor_plane();
  EXPECT_EQ(validate_tangent_plane(plane, 1e-3), "");
  plane.normal_W = {0, 0, 2};
  EXPECT_EQ(validate_tangent_plane(plane, 1e-3), "normal: must be a unit vector, got length 2");
  plane = floor_plane();
  plane.point_W.y = NAN;
  EXPECT_EQ(validate_tangent_plane(plane, 1e-3), "point: must be finite, got (0, nan, 0)");
  plane = floor_plane();
  plane.normal.damping = -2.0;
  EXPECT_EQ(validate_tangent_plane(plane, 1e-3),
            "normal_impedance.damping: must be finite and >= 0, got -2");
  plane = floor_plane();
  plane.tangential_damping = INFINITY;
  EXPECT_EQ(validate_tangent_plane(plane, 1e-3),
            "tangential_damping: must be finite and >= 0, got inf");
}

}  // namespace
}  // namespace haptic::engine
