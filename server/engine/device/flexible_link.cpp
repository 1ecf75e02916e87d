#include "engine/device/flexible_link.hpp"

#include <cassert>
#include <cmath>
#include <numbers>

namespace haptic::engine {
namespace {

/// Bisection of f on [a, b] where f(a) and f(b) differ in sign.
template <typename F>
double bisect(F&& f, double a, double b) {
  double fa = f(a);
  for (int i = 0; i < 200 && b - a > 1e-13 * std::abs(b); ++i) {
    const double m = 0.5 * (a + b);
    const double fm = f(m);
    if ((fm < 0.0) == (fa < 0.0)) {
      a = m;
      fa = fm;
    } else {
      b = m;
    }
  }
  return 0.5 * (a + b);
}

}  // namespace

double square_tube_area_moment(double h, double d) {
  const double inner = h - 2.0 * d;
  return (h * h * h * h - inner * inner * inner * inner) / 12.0;
}

double square_tube_area(double h, double d) {
  const double inner = h - 2.0 * d;
  return h * h - inner * inner;
}

double clamped_free_root(int k) {
  assert(k >= 1);
  const double pi = std::numbers::pi;
  return bisect([](double x) { return std::cos(x) + 1.0 / std::cosh(x); }, (k - 1) * pi, k * pi);
}

double clamped_free_frequency(const BeamParams& beam, int k) {
  const double pl = clamped_free_root(k);
  const double l2 = beam.length * beam.length;
  return pl * pl * std::sqrt(beam.E * beam.I / (beam.rho_A * l2 * l2));
}

double clamped_free_shape(int k, double x, double length) {
  const double pl = clamped_free_root(k);
  const double p = pl / length;
  const double sigma = (std::cosh(pl) + std::cos(pl)) / (std::sinh(pl) + std::sin(pl));
  const double px = p * x;
  return (std::cosh(px) - std::cos(px) - sigma * (std::sinh(px) - std::sin(px))) /
         std::sqrt(length);
}

double clamped_free_tip_value(int k, double length) {
  return clamped_free_shape(k, length, length);
}

double clamped_free_participation(int k, double length) {
  const double pl = clamped_free_root(k);
  return 2.0 * length * std::sqrt(length) / (pl * pl);
}

double hub_payload_characteristic(const HubPayloadBeamParams& b, double omega) {
  const double beta = std::sqrt(std::sqrt(b.rho * omega * omega / (b.E * b.I)));
  const double x = beta * b.L;
  const double Omega0 = b.J0 / b.rho;
  const double Omegap = b.M_p / b.rho;
  const double c = std::cos(x), s = std::sin(x), ch = std::cosh(x), sh = std::sinh(x);
  const double beta3 = beta * beta * beta;
  return c * sh - s * ch - 2.0 * Omegap * beta * s * sh - Omega0 * beta3 * (1.0 + c * ch) -
         beta3 * beta * Omegap * Omega0 * (c * sh - s * ch);
}

double hub_payload_first_frequency(const HubPayloadBeamParams& b) {
  // ω from βL: ω = (βL / L)² √(EI / ρ).
  const double scale = std::sqrt(b.E * b.I / b.rho) / (b.L * b.L);
  const auto f = [&](double x) { return hub_payload_characteristic(b, x * x * scale); };
  double previous = 0.05;
  double f_previous = f(previous);
  for (double x = 0.06; x <= 20.0; x += 0.01) {
    const double fx = f(x);
    if ((fx < 0.0) != (f_previous < 0.0)) {
      const double root = bisect(f, previous, x);
      return root * root * scale;
    }
    previous = x;
    f_previous = fx;
  }
  return 0.0;
}

}  // namespace haptic::engine
