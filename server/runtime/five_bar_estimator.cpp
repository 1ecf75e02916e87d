#include "runtime/five_bar_estimator.hpp"

#include "engine/device/single_joint_plant.hpp"

namespace haptic::runtime {

engine::StateEstimatorParams five_bar_estimator_params(int joint, double period_s) {
  engine::StateEstimatorParams params;  // the thesis' axial design
  params.sample_period = period_s;
  if (joint == 1) return params;
  const engine::SingleJointParams axial = engine::SingleJointParams::axial();
  const engine::SingleJointParams table =
      joint == 0 ? engine::SingleJointParams::horizontal() : engine::SingleJointParams::vertical();
  params.inertia = table.inertia;
  params.damping = table.damping;
  params.friction_coulomb = table.coulomb * (params.friction_coulomb / axial.coulomb);
  return params;
}

FiveBarStateEstimators::FiveBarStateEstimators(double period_s)
    : joints_{engine::StateEstimator(five_bar_estimator_params(0, period_s)),
              engine::StateEstimator(five_bar_estimator_params(1, period_s)),
              engine::StateEstimator(five_bar_estimator_params(2, period_s))} {}

void FiveBarStateEstimators::reset(const engine::FiveBarJoints& q_measured) {
  for (int j = 0; j < 3; ++j) joints_[j].reset(q_measured[j]);
}

engine::FiveBarJoints FiveBarStateEstimators::update(const engine::FiveBarJoints& q_measured,
                                                     const engine::FiveBarJoints& tau_applied,
                                                     const engine::FiveBarJoints& tau_user,
                                                     double /*dt: fixed at construction*/) {
  engine::FiveBarJoints velocity{};
  for (int j = 0; j < 3; ++j) {
    joints_[j].update(q_measured[j], tau_user[j], tau_applied[j]);
    velocity[j] = joints_[j].velocity();
  }
  return velocity;
}

}  // namespace haptic::runtime
