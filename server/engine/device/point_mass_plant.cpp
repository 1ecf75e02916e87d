#include "engine/device/point_mass_plant.hpp"

#include <cassert>
#include <cmath>

namespace haptic::engine {
namespace {

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
  assert(params.coulomb >= 0.0 && std::isfinite(params.coulomb));
  assert(params.actuator_lag >= 0.0 && std::isfinite(params.actuator_lag));
  assert(params.workspace_min.x <= params.workspace_max.x &&
         params.workspace_min.y <= params.workspace_max.y &&
         params.workspace_min.z <= params.workspace_max.z);
}

Vec3 PointMassPlant::through_lag(const Vec3& F_device, double h) {
  const double lag = params_.actuator_lag;
  if (!(lag > 0.0)) return F_device;
  // g(s) = F + (g₀ − F) e^{−s/τ} over the sub-step: its mean, and its value at the end.
  const double decay = std::exp(-h / lag);
  const double mean_weight = lag / h * (1.0 - decay);
  const Vec3 transient = lagged_force_ - F_device;
  lagged_force_ = F_device + transient * decay;
  return F_device + transient * mean_weight;
}

void PointMassPlant::advance_with_friction(double& x, double& v, double F, double m) const {
  const double c = params_.coulomb;
  if (v == 0.0 && std::abs(F) <= c) return;  // held
  const double direction = v != 0.0 ? (v > 0.0 ? 1.0 : -1.0) : (F > 0.0 ? 1.0 : -1.0);
  const double net = F - c * direction;  // friction opposes the motion, or its start
  const double x0 = x, v0 = v;
  coefficients_.advance(x, v, net / m);
  if (!(v * direction < 0.0)) return;
  // The velocity crossed zero within the sub-step: the axis stops there. The distance to the
  // stop, exact for the mass-damper: with v∞ = net/b, e^{−bt*/m} = −v∞/(v0 − v∞), and the
  // distance v∞ t* + (m/b) v0 (b → 0: −v0²/(2a)).
  const double b = params_.damping, h = coefficients_.h;
  if (b * h / m < 1e-9) {
    x = x0 - v0 * v0 / (2.0 * net / m);
  } else {
    const double terminal = net / b;
    const double stop_time = (m / b) * std::log((v0 - terminal) / -terminal);
    x = x0 + terminal * stop_time + (m / b) * v0;
  }
  v = 0.0;
}

void PointMassPlant::advance_exact(const Vec3& F) {
  const ExactMassDamperStep& c = coefficients_;
  const double m = params_.mass + added_mass_;
  if (params_.coulomb > 0.0) {
    advance_with_friction(state_.p_WT.x, state_.v_WT.x, F.x, m);
    advance_with_friction(state_.p_WT.y, state_.v_WT.y, F.y, m);
    advance_with_friction(state_.p_WT.z, state_.v_WT.z, F.z, m);
  } else {
    c.advance(state_.p_WT.x, state_.v_WT.x, F.x / m);
    c.advance(state_.p_WT.y, state_.v_WT.y, F.y / m);
    c.advance(state_.p_WT.z, state_.v_WT.z, F.z / m);
  }
  clamp_axis(state_.p_WT.x, state_.v_WT.x, params_.workspace_min.x, params_.workspace_max.x);
  clamp_axis(state_.p_WT.y, state_.v_WT.y, params_.workspace_min.y, params_.workspace_max.y);
  clamp_axis(state_.p_WT.z, state_.v_WT.z, params_.workspace_min.z, params_.workspace_max.z);
}

}  // namespace haptic::engine
