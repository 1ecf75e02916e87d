#pragma once
// Document 000's 1-DOF device (DC motor, gearbox, link under gravity) as the loop models it.
//
// The joint is the motor shaft: q = θ_m (rad), q̇ = θ̇_m (rad/s), τ the motor's torque (N·m). The
// tool point T is the link's end point E, on a circle of radius l in the device's x–y plane (y up,
// z the joint axis): p_WT = l (cos φ, sin φ, 0), φ = θ_L + α_c, θ_L = r θ_m (eqs. 3.1a, 4.2a). The
// scene's force F on the tool becomes the load torque τ_d = Jᵀ F (eqs. 4.1–4.3), and the motor
// torque adds gravity compensation and nothing else (direct torque control 5.2 with 6.7's τ_g):
//   τ_m = (r/η)(τ_g(θ_m) + τ_d)
// so the link moves as J_eff θ̈_m + B θ̇_m = (r/η)(τ_d + τ_e): the motor's own damping B (with the
// back-EMF) stays, which keeps the device passive. Only the force component along the circle's
// tangent can act on a 1-DOF link. A device declared without gravity (g = 0: a horizontal link)
// skips the cosine altogether.

#include "engine/device/dc_motor_plant.hpp"
#include "runtime/device_model.hpp"

namespace haptic::runtime {

class DcMotorModel final : public DeviceModel {
 public:
  /// `gravity`: compensate the link's weight (the device's capabilities.gravity).
  DcMotorModel(const engine::DcMotorParams& params, bool gravity) : params_(params), gravity_(gravity) {}

  void estimate(const DeviceReading& reading, double dt, bool first, JointState& joints) override;
  void kinematics(const JointState& joints, ToolReading& tool) override;
  /// kError for a non-finite force (the zero command is given: no torque, no compensation).
  DeviceStatus joint_command(const ToolCommand& command, const DeviceReading& reading,
                             const JointState& joints, double dt, DeviceCommand& out) override;

 private:
  engine::DcMotorParams params_;
  bool gravity_;
};

}  // namespace haptic::runtime
