#include "engine/device/exact_step.hpp"

#include <cmath>

namespace haptic::engine {
namespace {

/// g(z) = (z − 1 + e^{−z}) / z², the weight of the force in the position update (→ 1/2 as z → 0).
/// Below z = 0.1 the numerator cancels to z²/2, so the Taylor series is used instead:
/// g(z) = Σ_{n≥0} (−z)^n / (n + 2)!; ten terms leave a remainder below 1e-18.
double position_weight(double z) {
  if (z < 0.1) {
    double term = 0.5;  // (−z)^0 / 2!
    double sum = term;
    for (int n = 1; n < 10; ++n) {
      term *= -z / static_cast<double>(n + 2);
      sum += term;
    }
    return sum;
  }
  // Relative error of the direct form is about 2 eps / z <= 5e-15 here.
  return (z + std::expm1(-z)) / (z * z);
}

}  // namespace

ExactMassDamperStep ExactMassDamperStep::of(double m, double b, double h) {
  ExactMassDamperStep c;
  c.h = h;
  const double z = b / m * h;
  if (z > 0.0) {
    const double em1 = std::expm1(-z);  // e^{−z} − 1, exact to round-off even for tiny z
    c.decay = 1.0 + em1;
    c.phi = -em1 / z;
    c.g = position_weight(z);
  }
  return c;
}

}  // namespace haptic::engine
