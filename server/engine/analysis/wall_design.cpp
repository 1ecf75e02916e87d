#include "engine/analysis/wall_design.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>

namespace haptic::engine {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kZohDamping = kPi / 4.0;  // ζ of the hold's approximation (see the header)

double nyquist(const WallDesignParams& p) { return kPi / p.sample_period; }  // ω_N, rad/s

Complex jw(double omega) { return {0.0, omega}; }

/// The x in [a, b] minimising a unimodal f, to |b − a| <= tolerance (golden-section search).
template <typename F>
double golden_section_minimum(F&& f, double a, double b, double tolerance) {
  const double r = (std::sqrt(5.0) - 1.0) / 2.0;  // 0.618…
  double x1 = b - r * (b - a);
  double x2 = a + r * (b - a);
  double f1 = f(x1);
  double f2 = f(x2);
  while (b - a > tolerance) {
    if (f1 < f2) {
      b = x2;
      x2 = x1;
      f2 = f1;
      x1 = b - r * (b - a);
      f1 = f(x1);
    } else {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + r * (b - a);
      f2 = f(x2);
    }
  }
  return 0.5 * (a + b);
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

Complex zoh_approximation(const WallDesignParams& p, Complex s) {
  const double wn = nyquist(p);
  return wn * wn / (s * s + 2.0 * kZohDamping * wn * s + wn * wn);
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
  return P / (1.0 + zoh_approximation(p, s) * P * controller(p, controller_damping, s));
}

Complex transparency_weight(const WallDesignParams& p, Complex s) {
  return p.weight_cutoff / (s + p.weight_cutoff);
}

Complex uncertainty_loop(const WallDesignParams& p, double controller_damping, Complex s) {
  const Complex W = p.mass_uncertainty * p.mass * s + p.damping_uncertainty * p.damping;
  const Complex P = device_admittance(p, s);
  return -W * P / (1.0 + zoh_approximation(p, s) * P * controller(p, controller_damping, s));
}

bool nominal_loop_stable(const WallDesignParams& p, double controller_damping) {
  assert_valid(p);
  // s (ms + b)(s² + 2ζω_N s + ω_N²) + ω_N² (B_c s + K) = a4 s⁴ + a3 s³ + a2 s² + a1 s + a0.
  const double wn = nyquist(p);
  const double m = p.mass;
  const double b = p.damping;
  const double a4 = m;
  const double a3 = 2.0 * kZohDamping * wn * m + b;
  const double a2 = wn * wn * m + 2.0 * kZohDamping * wn * b;
  const double a1 = wn * wn * (b + controller_damping);
  const double a0 = wn * wn * p.wall_stiffness;
  if (a4 <= 0.0 || a3 <= 0.0 || a2 <= 0.0 || a1 <= 0.0 || a0 <= 0.0) return false;
  // Hurwitz determinants of a quartic: Δ2 = a3 a2 − a4 a1, Δ3 = a1 Δ2 − a3² a0.
  const double delta2 = a3 * a2 - a4 * a1;
  const double delta3 = a1 * delta2 - a3 * a3 * a0;
  return delta2 > 0.0 && delta3 > 0.0;
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
