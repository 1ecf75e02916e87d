#include "engine/analysis/wall_design.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>
#include <utility>

#include "engine/core/golden_section.hpp"

namespace haptic::engine {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kZohDamping = kPi / 4.0;  // ζ of the hold's approximation (see the header)

double nyquist(const WallDesignParams& p) { return kPi / p.sample_period; }  // ω_N, rad/s

Complex jw(double omega) { return {0.0, omega}; }

/// The x in [a, b] minimising a unimodal f, to |b − a| <= tolerance (golden-section search).
template <typename F>
double golden_section_minimum(F&& f, double a, double b, double tolerance) {
  const auto [lo, hi] = golden_section_narrow(std::forward<F>(f), a, b, tolerance, 10000);
  return 0.5 * (lo + hi);
}

void assert_valid(const WallDesignParams& p) {
  assert(p.mass > 0.0 && p.damping >= 0.0);
  assert(p.wall_stiffness > 0.0 && p.wall_damping > 0.0);
  assert(p.sample_period > 0.0 && p.weight_cutoff > 0.0);
  assert(p.mass_uncertainty >= 0.0 && p.mass_uncertainty < 1.0);
  assert(p.damping_uncertainty >= 0.0 && p.damping_uncertainty < 1.0);
  (void)p;
}

}  // namespace

Complex device_admittance(const WallDesignParams& p, Complex s) {
  return 1.0 / (p.mass * s + p.damping);
}

const char* hold_model_name(HoldModel hold) {
  switch (hold) {
    case HoldModel::kSecondOrder: return "second-order";
    case HoldModel::kHalfPeriodDelay: return "delay";
    case HoldModel::kPade: return "pade";
    case HoldModel::kExact: return "exact";
  }
  return "?";
}

Complex hold_response(const WallDesignParams& p, Complex s) {
  const double T = p.sample_period;
  switch (p.hold) {
    case HoldModel::kSecondOrder: {
      const double wn = nyquist(p);
      return wn * wn / (s * s + 2.0 * kZohDamping * wn * s + wn * wn);
    }
    case HoldModel::kHalfPeriodDelay:
      return std::exp(-s * (T / 2.0));
    case HoldModel::kPade:
      return (1.0 - s * (T / 4.0)) / (1.0 + s * (T / 4.0));
    case HoldModel::kExact: {
      const Complex x = s * T;
      // (1 − e^{−x}) / x loses its digits to cancellation near 0: there, its series.
      if (std::abs(x) < 1e-4) return 1.0 - x / 2.0 + x * x / 6.0;
      return (1.0 - std::exp(-x)) / x;
    }
  }
  return 1.0;
}

Complex virtual_wall(const WallDesignParams& p, Complex s) {
  return (p.wall_stiffness + p.wall_damping * s) / s;
}

Complex wall_admittance(const WallDesignParams& p, Complex s) {
  return s / (p.wall_stiffness + p.wall_damping * s);
}

Complex controller(const WallDesignParams& p, double controller_damping, Complex s) {
  return controller_damping + p.wall_stiffness / s;
}

Complex transmitted_admittance(const WallDesignParams& p, double controller_damping, Complex s) {
  const Complex P = device_admittance(p, s);
  return P / (1.0 + hold_response(p, s) * P * controller(p, controller_damping, s));
}

Complex transparency_weight(const WallDesignParams& p, Complex s) {
  return p.weight_cutoff / (s + p.weight_cutoff);
}

Complex uncertainty_loop(const WallDesignParams& p, double controller_damping, Complex s) {
  const Complex W = p.mass_uncertainty * p.mass * s + p.damping_uncertainty * p.damping;
  const Complex P = device_admittance(p, s);
  return -W * P / (1.0 + hold_response(p, s) * P * controller(p, controller_damping, s));
}

bool nominal_loop_stable(const WallDesignParams& p, double controller_damping) {
  assert_valid(p);
  const double m = p.mass;
  const double b = p.damping;
  const double K = p.wall_stiffness;
  switch (p.hold) {
    case HoldModel::kSecondOrder: {
      // s (ms + b)(s² + 2ζω_N s + ω_N²) + ω_N² (B_c s + K) = a4 s⁴ + a3 s³ + a2 s² + a1 s + a0.
      const double wn = nyquist(p);
      const double a4 = m;
      const double a3 = 2.0 * kZohDamping * wn * m + b;
      const double a2 = wn * wn * m + 2.0 * kZohDamping * wn * b;
      const double a1 = wn * wn * (b + controller_damping);
      const double a0 = wn * wn * K;
      if (a4 <= 0.0 || a3 <= 0.0 || a2 <= 0.0 || a1 <= 0.0 || a0 <= 0.0) return false;
      // Hurwitz determinants of a quartic: Δ2 = a3 a2 − a4 a1, Δ3 = a1 Δ2 − a3² a0.
      const double delta2 = a3 * a2 - a4 * a1;
      const double delta3 = a1 * delta2 - a3 * a3 * a0;
      return delta2 > 0.0 && delta3 > 0.0;
    }
    case HoldModel::kPade: {
      // s (ms + b)(1 + θs) + (1 − θs)(B_c s + K), θ = T/4: a3 s³ + a2 s² + a1 s + a0.
      const double theta = p.sample_period / 4.0;
      const double a3 = theta * m;
      const double a2 = m + theta * (b - controller_damping);
      const double a1 = b + controller_damping - theta * K;
      const double a0 = K;
      if (a3 <= 0.0 || a2 <= 0.0 || a1 <= 0.0 || a0 <= 0.0) return false;
      return a2 * a1 > a3 * a0;  // the cubic's Hurwitz determinant Δ2
    }
    case HoldModel::kHalfPeriodDelay:
    case HoldModel::kExact:
      return right_half_plane_roots(p, controller_damping) == 0;
  }
  return false;
}

int right_half_plane_roots(const WallDesignParams& p, double controller_damping) {
  assert_valid(p);
  const double m = p.mass;
  const double K = p.wall_stiffness;
  const double B_c = controller_damping;
  const auto dominant = [&](double omega) {  // s (ms + b) at s = jω
    const Complex s = jw(omega);
    return s * (m * s + p.damping);
  };
  const auto characteristic = [&](double omega) {
    const Complex s = jw(omega);
    return dominant(omega) + hold_response(p, s) * (B_c * s + K);
  };
  // Beyond ω_x, |s (ms + b)| >= m ω² > B_c ω + K >= |ZOH (B_c s + K)|: f stays within 90° of its
  // dominant term, whose phase rises monotonically to π.
  const double omega_x = 1.01 * (std::abs(B_c) + std::sqrt(B_c * B_c + 4.0 * m * K)) / (2.0 * m);
  // Steps: 2 % of ω (at least of 1 rad/s), and at most 1/64 of e^{−jωT}'s period.
  const double max_step = 2.0 * kPi / (64.0 * p.sample_period);
  double omega = 0.0;
  Complex f = characteristic(0.0);  // K, phase 0
  double phase = 0.0;
  while (omega < omega_x) {
    double step = std::min({0.02 * std::max(omega, 1.0), max_step, omega_x - omega});
    Complex next;
    double turn;
    for (;;) {  // halve the step until the phase turns less than 0.3 rad in it
      next = characteristic(omega + step);
      turn = std::arg(next / f);
      if (std::abs(turn) < 0.3 || step < 1e-9 * std::max(omega, 1.0)) break;
      step /= 2.0;
    }
    phase += turn;
    omega += step;
    f = next;
  }
  // phase = arg s(ms + b) at ω_x + the deviation (|·| < π/2) + 2πk; as ω → ∞ it reaches π + 2πk.
  const double deviation = std::arg(f / dominant(omega_x));
  const double dominant_phase = kPi / 2.0 + std::atan2(m * omega_x, p.damping);
  const double k = std::round((phase - dominant_phase - deviation) / (2.0 * kPi));
  // Over −∞ < ω < ∞ the phase changes by 2 (π + 2πk); the roots on the right number
  // (n − Δ/π) / 2 with n = 2, the degree of the dominant term.
  return static_cast<int>(-2.0 * k);
}

double transparency_index(const WallDesignParams& p, double controller_damping) {
  assert_valid(p);
  constexpr double kPointsPerDecade = 400.0;
  const double omega_min = 1e-2;
  const double omega_max = 1e3 * nyquist(p);
  const double du = std::log(10.0) / kPointsPerDecade;
  const int intervals =
      static_cast<int>(std::ceil(std::log(omega_max / omega_min) / du));
  const double step = std::log(omega_max / omega_min) / intervals;
  // ∫ f(ω) dω = ∫ f(e^u) e^u du.
  const auto integrand = [&](double u) {
    const double omega = std::exp(u);
    const Complex s = jw(omega);
    const Complex e = transparency_weight(p, s) *
                      (wall_admittance(p, s) - transmitted_admittance(p, controller_damping, s));
    return std::norm(e) * omega;
  };
  const double u0 = std::log(omega_min);
  double sum = 0.5 * (integrand(u0) + integrand(u0 + intervals * step));
  for (int i = 1; i < intervals; ++i) sum += integrand(u0 + i * step);
  const double tail = p.weight_cutoff * p.weight_cutoff /
                      (p.wall_damping * p.wall_damping * omega_max);
  return (sum * step + tail) / kPi;
}

double robust_stability_norm(const WallDesignParams& p, double controller_damping) {
  assert_valid(p);
  constexpr double kPointsPerDecade = 2000.0;
  const double u_min = std::log(0.1);
  const double u_max = std::log(nyquist(p));
  const int intervals = static_cast<int>(
      std::ceil((u_max - u_min) / (std::log(10.0) / kPointsPerDecade)));
  const double step = (u_max - u_min) / intervals;
  const auto gain = [&](double u) {
    return std::abs(uncertainty_loop(p, controller_damping, jw(std::exp(u))));
  };
  int best = 0;
  double best_gain = gain(u_min);
  for (int i = 1; i <= intervals; ++i) {
    const double g = gain(u_min + i * step);
    if (g > best_gain) {
      best_gain = g;
      best = i;
    }
  }
  const double a = u_min + std::max(best - 1, 0) * step;
  const double b = u_min + std::min(best + 1, intervals) * step;
  const double u_peak =
      golden_section_minimum([&](double u) { return -gain(u); }, a, b, 1e-9);
  return std::max(best_gain, gain(u_peak));
}

double to_db(double gain) { return 20.0 * std::log10(gain); }

OptimalWallDesign optimise_controller_damping(const WallDesignParams& p, double lo, double hi) {
  assert_valid(p);
  assert(lo > 0.0 && lo < hi);
  constexpr int kScanIntervals = 60;
  const double u_lo = std::log(lo);
  const double step = (std::log(hi) - u_lo) / kScanIntervals;
  const auto j_of_u = [&](double u) { return transparency_index(p, std::exp(u)); };
  int best = 0;
  double best_j = j_of_u(u_lo);
  for (int i = 1; i <= kScanIntervals; ++i) {
    const double j = j_of_u(u_lo + i * step);
    if (j < best_j) {
      best_j = j;
      best = i;
    }
  }
  const double a = u_lo + std::max(best - 1, 0) * step;
  const double b = u_lo + std::min(best + 1, kScanIntervals) * step;
  const double u_opt = golden_section_minimum(j_of_u, a, b, 1e-6);

  OptimalWallDesign out;
  out.controller_damping = std::exp(u_opt);
  out.transparency_index = transparency_index(p, out.controller_damping);
  out.robust_stability_norm = robust_stability_norm(p, out.controller_damping);
  out.nominal_loop_stable = nominal_loop_stable(p, out.controller_damping);
  out.robustly_stable = out.nominal_loop_stable && out.robust_stability_norm <= 1.0;
  return out;
}

}  // namespace haptic::engine
