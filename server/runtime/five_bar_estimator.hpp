#pragma once
// Madill's non-linear state estimator (1998, ch. 6.3; engine/control/state_estimator) on each joint
// of the five-bar, as the five-bar model's velocity source (runtime/five_bar_model).
//
// The thesis designs it for the axial joint q1 only (L3061–3129: J, B of Table 5.4, Q = diag(1, 41.6),
// R = 0.1, f0 = 0.061 N·m, v0 = 0.03 rad/s). At haptic speeds each joint is a decoupled SISO plant
// (L2388), so the other two joints get the same design with their own Table 5.4 inertia and damping,
// and the hand-tuned friction scaled from the identified one in the axial joint's ratio
// (0.061 / 0.088) [inference: the thesis tunes only q1]. Each joint's estimator is fed the saturated
// joint torque and the operator's joint torque, as L3230 prescribes.

#include "engine/control/state_estimator.hpp"
#include "runtime/five_bar_model.hpp"

namespace haptic::runtime {

/// Estimator parameters for five-bar joint `joint` (0 horizontal, 1 axial, 2 vertical) at loop
/// period `period_s` (s).
engine::StateEstimatorParams five_bar_estimator_params(int joint, double period_s);

class FiveBarStateEstimators final : public FiveBarVelocityEstimator {
 public:
  /// Solves three Riccati equations: construct off the loop.
  explicit FiveBarStateEstimators(double period_s);

  void reset(const engine::FiveBarJoints& q_measured) override;
  engine::FiveBarJoints update(const engine::FiveBarJoints& q_measured,
                               const engine::FiveBarJoints& tau_applied,
                               const engine::FiveBarJoints& tau_user, double dt) override;

  const engine::StateEstimator& joint(int index) const { return joints_[index]; }

 private:
  engine::StateEstimator joints_[3];
};

}  // namespace haptic::runtime
