#include "engine/device/point_mass_plant.hpp"

#include <cassert>
#include <cmath>

namespace haptic::engine {
namespace {

/// One axis of m v' = F − b v over h with F constant (Eom et al. eq. 5, exact solution).
void advance_axis(double& x, double& v, double F, double m, double b, double h) {
  const double a = b / m;
  if (a * h < 1e-12) {
    // Undamped limit: the exact solution of m v' = F.
    x += v * h + 0.5 * F / m * h * h;
    v += F / m * h;
    return;
  }
  const double decay = -std::expm1(-a * h);  // 1 − e^{−ah}, without cancellation for small ah
  const double v_terminal = F / b;
  x += v_terminal * h + (v - v_terminal) * decay / a;
  v = v_terminal + (v - v_terminal) * (1.0 - decay);
}

/// An inelastic stop at the workspace box.
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
  assert(params.mass > 0.0 && params.damping >= 0.0 && params.substeps >= 1);
}

void PointMassPlant::advance_exact(const Vec3& F, double h) {
  const double m = params_.mass;
  const double b = params_.damping;
  advance_axis(state_.p_WT.x, state_.v_WT.x, F.x, m, b, h);
  advance_axis(state_.p_WT.y, state_.v_WT.y, F.y, m, b, h);
  advance_axis(state_.p_WT.z, state_.v_WT.z, F.z, m, b, h);
  clamp_axis(state_.p_WT.x, state_.v_WT.x, params_.workspace_min.x, params_.workspace_max.x);
  clamp_axis(state_.p_WT.y, state_.v_WT.y, params_.workspace_min.y, params_.workspace_max.y);
  clamp_axis(state_.p_WT.z, state_.v_WT.z, params_.workspace_min.z, params_.workspace_max.z);
}

}  // namespace haptic::engine
