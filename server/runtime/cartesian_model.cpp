#include "runtime/cartesian_model.hpp"

namespace haptic::runtime {

void CartesianModel::estimate(const DeviceReading& reading, double, bool, JointState& joints) {
  for (std::size_t i = 0; i < 3; ++i) {
    joints.q[i] = reading.q[i];
    joints.q_dot[i] = reading.q_dot[i];
  }
}

void CartesianModel::kinematics(const JointState& joints, ToolReading& tool) {
  tool.p_WT = {joints.q[0], joints.q[1], joints.q[2]};
  tool.v_WT = {joints.q_dot[0], joints.q_dot[1], joints.q_dot[2]};
}

DeviceStatus CartesianModel::joint_command(const ToolCommand& command, const DeviceReading&,
                                           const JointState&, double, DeviceCommand& out) {
  if (!engine::is_finite(command.F_T_W)) {
    out = {};
    return DeviceStatus::kError;
  }
  out.tau[0] = command.F_T_W.x;
  out.tau[1] = command.F_T_W.y;
  out.tau[2] = command.F_T_W.z;
  return DeviceStatus::kOk;
}

}  // namespace haptic::runtime
