#pragma once
// Virtual walls on one joint (Madill 1998, ch. 6), evaluated once per loop period:
//  - conventional (implicit force control, §6.1, L2869–2913, eq. 6.2):
//      τ = −H(q_m) (K_p q_m + K_d v),  v = the backward difference (q_m[k] − q_m[k−1]) / T passed
//      through the first-order low-pass ω0 / (s + ω0);
//  - estimator-based (§6.3, Fig. 6.19, L3246–3262):
//      u_c = −H(q̂) (K_p q̂ + K_d q̇̂),  q̂, q̇̂ from StateEstimator.
// Sign convention (the thesis', L3259: "the user enters the virtual wall when the joint angle
// becomes positive"): the wall surface is at q = 0 and its inside is q > 0; H(q) = 1 for q > 0 and
// 0 for q ≤ 0, so the torque is exactly zero on the first sample outside (L3260: "the output
// torque is completely eliminated the instant the virtual wall is exited", unlike Colgate and
// Brown's zero-input response). A wall on the other side: negate q going in and τ coming out.
// Inside, K_p q + K_d v can turn negative while the joint leaves fast, and the wall then pulls;
// that is the thesis' law as written and is kept.
// Both return the motor command in N·m; the D/A saturation is the device's (τ_d = 7.23 N·m).

#include <numbers>
#include <string>

#include "engine/control/state_estimator.hpp"

namespace haptic::engine {

/// Gains of a joint wall. Defaults: the conventional wall's best (K_p = 400, K_d = 0, "slightly
/// beyond the maximum gain for acceptable performance", L2903); the estimator wall of Figs. 6.20–
/// 6.21 uses K_p = 800, K_d = 5 (L3262).
struct JointWallParams {
  double stiffness = 400.0;  // K_p. Unit: N·m/rad. >= 0.
  double damping = 0.0;      // K_d. Unit: N·m·s/rad. >= 0.
  /// ω0 of the conventional wall's velocity filter (eq. 6.2). §6.1 gives no value; the default is
  /// the 10 Hz first-order filter the thesis compares the estimator against (L3280). Unused by
  /// the estimator wall. Unit: rad/s. > 0.
  double velocity_cutoff = 2.0 * std::numbers::pi * 10.0;
  double sample_period = 1e-3;  // T. Unit: s. > 0.

  /// Empty when usable, otherwise one message naming the first bad parameter.
  std::string validate() const;
};

/// H(q): 1 inside the wall (q > 0), 0 on and outside it.
constexpr double wall_gate(double q) { return q > 0.0 ? 1.0 : 0.0; }

/// The conventional wall of §6.1 on the measured (quantized) angle.
class ConventionalJointWall {
 public:
  explicit ConventionalJointWall(const JointWallParams& params);

  /// Forgets the velocity: the next sample's backward difference is taken from q_previous.
  void reset(double q_previous);

  /// τ[k] from the measurement q_m[k] (rad). Unit: N·m. Updates the velocity filter in and out of
  /// the wall, so the velocity is current on entry.
  double torque(double q_measured);

  /// The filtered velocity after the last sample. Unit: rad/s.
  double velocity() const { return velocity_; }
  const JointWallParams& params() const { return params_; }

 private:
  JointWallParams params_;
  double filter_weight_;  // 1 − e^{−ω0 T}: the exact ZOH discretization of ω0 / (s + ω0)
  double q_previous_ = 0.0;
  double velocity_ = 0.0;
};

/// u_c = −H(q̂)(K_p q̂ + K_d q̇̂) (Fig. 6.19). Unit: N·m.
inline double estimator_wall_torque(const JointWallParams& params, double q_hat,
                                    double q_dot_hat) {
  return -wall_gate(q_hat) * (params.stiffness * q_hat + params.damping * q_dot_hat);
}

/// The estimator-based wall of Fig. 6.19: each tick, the command from the current estimate, then
/// the estimator advanced with the measurement, the operator's torque and that command.
class EstimatorJointWall {
 public:
  EstimatorJointWall(const JointWallParams& params, const StateEstimatorParams& estimator);

  /// Starts the estimate at rest at q (rad).
  void reset(double q) { estimator_.reset(q, 0.0); }

  /// u_c[k] from the measurement q_m[k] (rad) and the operator's torque τ_u[k] (N·m).
  double torque(double q_measured, double user_torque) {
    const double command =
        estimator_wall_torque(params_, estimator_.position(), estimator_.velocity());
    estimator_.update(q_measured, user_torque, command);
    return command;
  }

  const StateEstimator& estimator() const { return estimator_; }
  const JointWallParams& params() const { return params_; }

 private:
  JointWallParams params_;
  StateEstimator estimator_;
};

}  // namespace haptic::engine
