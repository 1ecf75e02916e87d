#include "runtime/dc_motor_model.hpp"

namespace haptic::runtime {

void DcMotorModel::estimate(const DeviceReading& reading, double, bool, JointState& joints) {
  joints.q[0] = reading.q[0];
  joints.q_dot[0] = reading.q_dot[0];
}

void DcMotorModel::kinematics(const JointState& joints, ToolReading& tool) {
  engine::dc_motor_end_point(params_, joints.q[0], joints.q_dot[0], tool.p_WT, tool.v_WT);
}

DeviceStatus DcMotorModel::joint_command(const ToolCommand& command, const DeviceReading&,
                                         const JointState& joints, double, DeviceCommand& out) {
  out = {};
  if (!engine::is_finite(command.F_T_W)) return DeviceStatus::kError;
  const double theta_m = joints.q[0];
  const double tau_d = engine::external_joint_torque(params_, params_.r * theta_m, {command.F_T_W, {}});
  const double tau_g = gravity_ ? params_.gravity_torque(theta_m) : 0.0;
  out.tau[0] = params_.r / params_.eta * (tau_g + tau_d);
  return DeviceStatus::kOk;
}

}  // namespace haptic::runtime
