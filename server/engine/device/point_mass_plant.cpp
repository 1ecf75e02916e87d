#include "engine/device/point_mass_plant.hpp"

#include <cassert>
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

/// One axis of m v' = F − b v over one sub-step with F constant (Eom et al. eq. 5), solved
/// exactly with the weights of PointMassPlant::coefficients_for.
void advance_axis(double& x, double& v, double accel, double h, double decay, double phi, double g) {
  x += h * (v * phi + accel * h * g);
  v = v * decay + accel * h * phi;
}

/// An inelastic stop at the workspace box: the position is held at the bound and only the outward
/// velocity component is removed, so the tool can still slide along the face.
void clamp_axis(double& x, double& v, double lo, double hi) {
  if (x < lo) {
    x = lo;
    if (v < 0.0) v = 0.0;
  } else if (x > hi) {
    x = hi;
    if (v > 0.0) v = 0.0;
  }
}

}  // namespace

PointMassPlant::PointMassPlant(const PointMassParams& params, const PointMassState& initial)
    : params_(params), state_(initial) {
  assert(params.mass > 0.0 && std::isfinite(params.mass));
  assert(params.damping >= 0.0 && std::isfinite(params.damping));
  assert(params.substeps >= 1);
  assert(params.workspace_min.x <= params.workspace_max.x &&
         params.workspace_min.y <= params.workspace_max.y &&
         params.workspace_min.z <= params.workspace_max.z);
}

/// One axis of m v' = F − b v over h with F constant (Eom et al. eq. 5), solved exactly. With
/// a = b/m and z = a h:
///   v1 = v0 e^{−z} + (F/m) h φ(z),            φ(z) = (1 − e^{−z}) / z,
///   x1 = x0 + v0 h φ(z) + (F/m) h² g(z),      g(z) = (z − 1 + e^{−z}) / z².
/// This is the textbook form v0 e + (F/b)(1 − e), x0 + (F/b) h + (v0 − F/b)(1 − e)/a regrouped so
/// that nothing divides by b and the large terms (F/b) h and (F/b)(1 − e)/a never cancel; b = 0
/// is the limit φ = 1, g = 1/2.
PointMassPlant::StepCoefficients PointMassPlant::coefficients_for(double h) const {
  StepCoefficients c;
  c.h = h;
  const double z = params_.damping / (params_.mass + added_mass_) * h;
  if (z > 0.0) {
    const double em1 = std::expm1(-z);  // e^{−z} − 1, exact to round-off even for tiny z
    c.decay = 1.0 + em1;
    c.phi = -em1 / z;
    c.g = position_weight(z);
  }
  return c;
}

void PointMassPlant::advance_exact(const Vec3& F) {
  const StepCoefficients& c = coefficients_;
  const double m = params_.mass + added_mass_;
  advance_axis(state_.p_WT.x, state_.v_WT.x, F.x / m, c.h, c.decay, c.phi, c.g);
  advance_axis(state_.p_WT.y, state_.v_WT.y, F.y / m, c.h, c.decay, c.phi, c.g);
  advance_axis(state_.p_WT.z, state_.v_WT.z, F.z / m, c.h, c.decay, c.phi, c.g);
  clamp_axis(state_.p_WT.x, state_.v_WT.x, params_.workspace_min.x, params_.workspace_max.x);
  clamp_axis(state_.p_WT.y, state_.v_WT.y, params_.workspace_min.y, params_.workspace_max.y);
  clamp_axis(state_.p_WT.z, state_.v_WT.z, params_.workspace_min.z, params_.workspace_max.z);
}

}  // namespace haptic::engine
