#include "runtime/five_bar_model.hpp"

#include <utility>

#include "engine/device/joint_friction.hpp"

namespace haptic::runtime {

FiveBarModel::FiveBarModel(const engine::FiveBarParams& params, double velocity_cutoff)
    : params_(params) {
  difference_.cutoff = velocity_cutoff;
}

void FiveBarModel::set_velocity_estimator(std::unique_ptr<FiveBarVelocityEstimator> estimator) {
  estimator_ = std::move(estimator);
  restart_ = true;
}

void FiveBarModel::estimate(const DeviceReading& reading, double dt, bool first, JointState& joints) {
  const engine::FiveBarJoints q{reading.q[0], reading.q[1], reading.q[2]};
  engine::FiveBarJoints q_dot{};
  if (first || restart_) {
    difference_.reset(q);
    if (estimator_) estimator_->reset(q);
    applied_ = {};
    restart_ = false;
  } else if (estimator_) {
    const engine::FiveBarJoints tau_user{reading.tau_sensor[0], reading.tau_sensor[1],
                                         reading.tau_sensor[2]};
    q_dot = estimator_->update(q, applied_, tau_user, dt);
  } else {
    q_dot = difference_.update(q, dt);
  }
  joints.q = {q[0], q[1], q[2]};
  joints.q_dot = {q_dot[0], q_dot[1], q_dot[2]};
}

void FiveBarModel::kinematics(const JointState& joints, ToolReading& tool) {
  const engine::FiveBarJoints q{joints.q[0], joints.q[1], joints.q[2]};
  tool.p_WT = engine::five_bar_tip_position(params_, q);
  const engine::FiveBarMatrix J = engine::five_bar_jacobian(params_, q);
  const JointVector& w = joints.q_dot;
  tool.v_WT = {J[0][0] * w[0] + J[0][1] * w[1] + J[0][2] * w[2],
               J[1][0] * w[0] + J[1][1] * w[1] + J[1][2] * w[2],
               J[2][0] * w[0] + J[2][1] * w[1] + J[2][2] * w[2]};
}

DeviceStatus FiveBarModel::joint_command(const ToolCommand& command, const DeviceReading&,
                                         const JointState& joints, double, DeviceCommand& out) {
  out = {};
  applied_ = {};
  if (!engine::is_finite(command.F_T_W)) return DeviceStatus::kError;
  const engine::FiveBarJoints q{joints.q[0], joints.q[1], joints.q[2]};
  const engine::FiveBarJoints tau = engine::five_bar_joint_torque(params_, q, command.F_T_W);
  for (std::size_t i = 0; i < 3; ++i) {
    applied_[i] = engine::saturate(tau[i], params_.torque_limit[i]);  // the D/A limit (L3237)
    out.tau[i] = applied_[i];
  }
  return DeviceStatus::kOk;
}

}  // namespace haptic::runtime
