#pragma once
// The model of a device whose joints are the tool point's Cartesian axes (the point mass, or a
// driver that does its own kinematics): q = p_WT, q̇ = v_WT measured, τ = F_T_W (J = 𝟙).

#include "runtime/device_model.hpp"

namespace haptic::runtime {

class CartesianModel final : public DeviceModel {
 public:
  void estimate(const DeviceReading& reading, double dt, bool first, JointState& joints) override;
  void kinematics(const JointState& joints, ToolReading& tool) override;
  /// kError for a non-finite force (the zero command is given).
  DeviceStatus joint_command(const ToolCommand& command, const DeviceReading& reading,
                             const JointState& joints, double dt, DeviceCommand& out) override;
};

}  // namespace haptic::runtime
