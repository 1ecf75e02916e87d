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
  assert(params.workspace_min.x <= params.workspace_max.x &&
         params.workspace_min.y <= params.workspace_max.y &&
         params.workspace_min.z <= params.workspace_max.z);
}

void PointMassPlant::advance_exact(const Vec3& F) {
  const ExactMassDamperStep& c = coefficients_;
  const double m = params_.mass + added_mass_;
  c.advance(state_.p_WT.x, state_.v_WT.x, F.x / m);
  c.advance(state_.p_WT.y, state_.v_WT.y, F.y / m);
  c.advance(state_.p_WT.z, state_.v_WT.z, F.z / m);
  clamp_axis(state_.p_WT.x, state_.v_WT.x, params_.workspace_min.x, params_.workspace_max.x);
  clamp_axis(state_.p_WT.y, state_.v_WT.y, params_.workspace_min.y, params_.workspace_max.y);
  clamp_axis(state_.p_WT.z, state_.v_WT.z, params_.workspace_min.z, params_.workspace_max.z);
}

}  // namespace haptic::engine
