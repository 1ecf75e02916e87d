#include "engine/safety/passivity.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace haptic::engine {
namespace {

std::string bad(const char* name, const char* rule, double value) {
  char buffer[96];
  std::snprintf(buffer, sizeof buffer, "%s: must be finite and %s, got %g", name, rule, value);
  return buffer;
}

}  // namespace

PassivityControllerParams passivity_params_for_device(double m, double T,
                                                      double velocity_resolution) {
  PassivityControllerParams params;
  params.period = T;
  params.max_damping = m / T;
  params.velocity_threshold = velocity_resolution;
  return params;
}

std::string validate_passivity(const PassivityControllerParams& params) {
  if (!(std::isfinite(params.period) && params.period > 0.0)) {
    return bad("period", "> 0", params.period);
  }
  if (!(std::isfinite(params.max_damping) && params.max_damping >= 0.0)) {
    return bad("max_damping", ">= 0", params.max_damping);
  }
  if (!(std::isfinite(params.velocity_threshold) && params.velocity_threshold >= 0.0)) {
    return bad("velocity_threshold", ">= 0", params.velocity_threshold);
  }
  return {};
}

PassivityStep PassivityController::apply(const Vec3& F_T_W, const Vec3& v_WT, const Vec3& p_WT) {
  PassivityStep step;
  step.F_T_W = F_T_W;
  if (!is_finite(F_T_W) || !is_finite(v_WT) || !is_finite(p_WT)) {
    // A non-finite request is the force guard's to fault. Booked, it would leave the observed
    // energy NaN for good (no comparison with NaN is true) and the controller off until restart.
    reset();
    return step;
  }
  const double T = params_.period;
  const bool held = observer_.mode() == PassivityObserverMode::kHeldForceWork;
  if (held) observer_.complete_period(p_WT);  // E(n−1): exact through the last period
  const double E_observed = observer_.energy() - T * dot(F_T_W, v_WT);  // E_obs(n)
  const double v_squared = dot(v_WT, v_WT);
  const double v_min = params_.velocity_threshold;
  // v_squared > 0 also guards v_min = 0 against dividing by zero.
  if (E_observed < 0.0 && v_squared > 0.0 && v_squared >= v_min * v_min) {
    double alpha = -E_observed / (T * v_squared);  // the damping that brings E_obs back to 0
    if (alpha > params_.max_damping) {
      alpha = params_.max_damping;
      step.limited = true;
    }
    step.alpha = alpha;
    step.F_T_W -= alpha * v_WT;
    dissipated_ += alpha * T * v_squared;
  }
  step.energy = E_observed + step.alpha * T * v_squared;
  if (held) {
    observer_.sent(step.F_T_W, p_WT);  // booked when the period completes
  } else {
    observer_.add(step.energy - observer_.energy());
  }
  return step;
}

}  // namespace haptic::engine
