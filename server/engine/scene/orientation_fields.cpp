#include "engine/scene/orientation_fields.hpp"

#include <cmath>
#include <numbers>

#include "engine/core/parameter_checks.hpp"
#include "engine/scene/fields.hpp"

namespace haptic::engine {

namespace {

/// |q| within 1e-6 of 1: the target of an orientation field is a rotation, not a scaled one.
std::string check_target(const Quat& R_WG) {
  if (!is_unit(R_WG)) {
    return bad_parameter("R_WG", "norm must be 1 (a finite unit quaternion)", norm(R_WG));
  }
  return {};
}


}  // namespace

std::string validate_orientation_spring(const OrientationSpringSpec& spec, double T) {
  if (std::string m = check_target(spec.R_WG); !m.empty()) return m;
  if (!is_non_negative(spec.max_torque)) {
    return bad_parameter("max_torque", "must be finite and >= 0 (0: no clip)", spec.max_torque);
  }
  return validate_impedance(ImpedanceParams{spec.stiffness, spec.damping, 0.0}, T);
}

std::string validate_orientation_detent(const OrientationDetentSpec& spec) {
  if (std::string m = check_target(spec.R_WG); !m.empty()) return m;
  if (!is_positive(spec.depth)) return bad_parameter("depth", "must be finite and > 0", spec.depth);
  if (!is_positive(spec.radius)) return bad_parameter("radius", "must be finite and > 0", spec.radius);
  if (!is_non_negative(spec.rim_height)) {
    return bad_parameter("rim_height", "must be finite and >= 0", spec.rim_height);
  }
  if (!is_positive(spec.rim_width)) {
    return bad_parameter("rim_width", "must be finite and > 0", spec.rim_width);
  }
  // Beyond π the angle folds back (|θ| ≤ π), so a profile reaching past it would not be C¹.
  if (spec.radius + spec.rim_width > std::numbers::pi) {
    return bad_parameter("rim_width", "must keep radius + rim_width <= pi rad",
                         spec.radius + spec.rim_width);
  }
  if (!is_non_negative(spec.damping)) {
    return bad_parameter("damping", "must be finite and >= 0", spec.damping);
  }
  return {};
}

ImpedanceWeights orientation_spring_weights(const OrientationSpringSpec& spec, double T) {
  if (spec.law == ContactLaw::kVelocity) return ImpedanceWeights{};
  return impedance_weights(ImpedanceParams{spec.stiffness, spec.damping, 0.0},
                           discretization_of(spec.law), T);
}

OrientationSample OrientationSpringState::update(const OrientationSpringSpec& spec,
                                                 const Quat& R_WT, const Vec3& w_WT, double T) {
  const Vec3 theta = orientation_error_W(R_WT, spec.R_WG);
  OrientationSample out;
  out.has_potential = true;
  out.U = 0.5 * spec.stiffness * dot(theta, theta);
  if (spec.law == ContactLaw::kVelocity) {
    out.tau_T_W = clip_norm(-spec.stiffness * theta - spec.damping * w_WT, spec.max_torque);
  } else {
    // The log map's branch flips where |θ| passes π; a jump that large is never a real motion
    // within one tick, so the filters restart there as they start: from the measured rate.
    const bool restart = !started || norm(theta - theta_previous) > std::numbers::pi;
    const double d[3] = {-theta.x, -theta.y, -theta.z};
    const double rate[3] = {-w_WT.x, -w_WT.y, -w_WT.z};
    double f[3];
    for (std::size_t i = 0; i < 3; ++i) {
      if (restart) filters[i].reset(d[i] - T * rate[i], rate[i]);
      f[i] = filters[i].update(d[i]);
    }
    out.tau_T_W = clip_norm(Vec3{f[0], f[1], f[2]}, spec.max_torque);
    started = true;
  }
  theta_previous = theta;
  if (spec.max_torque > 0.0 && spec.stiffness * norm(theta) > spec.max_torque) {
    // The clipped spring's potential (as SpringFieldSpec's): exact for b = 0.
    const double limit = spec.max_torque;
    out.U = limit * norm(theta) - limit * limit / (2.0 * spec.stiffness);
  }
  return out;
}

OrientationSample evaluate_orientation_detent(const OrientationDetentSpec& spec, const Quat& R_WT,
                                              const Vec3& w_WT) {
  const Vec3 theta = orientation_error_W(R_WT, spec.R_WG);
  const double rho = norm(theta);
  const PotentialProfile profile =
      detent_profile(spec.depth, spec.radius, spec.rim_height, spec.rim_width, rho);
  OrientationSample out;
  out.U = profile.U;
  out.has_potential = true;
  // ∇ρ = θ/ρ; at the target U′(0) = 0, so the direction does not matter there.
  if (rho > 0.0) out.tau_T_W = (-profile.dU_df / rho) * theta;
  if (rho < spec.radius + spec.rim_width) out.tau_T_W -= spec.damping * w_WT;
  return out;
}

}  // namespace haptic::engine
