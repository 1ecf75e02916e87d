#pragma once
// Document 001's device as the loop models it: the 2-DOF parallel (five-bar) mechanism of
// engine/device/parallel_2dof with a disturbance observer on each Cartesian axis
// (engine/control/disturbance_observer; Eom, Suh, Yi, eqs. 2–5, Fig. 1).
//
// The joints are the two motor angles q = (q_1, q_2) (rad) with their rates; the tool point T is
// the end effector in the device plane, p_WT = (x, y, 0) = forward kinematics of q, v_WT = J q̇;
// the plane is horizontal, so there is no gravity load. Per tick k (the loop's period T must be
// the observer's sample_period):
//   1. the handle's force sensor reads the operator's force F_h,k (DeviceReading::F_sensor_W; the
//      observer needs it, otherwise it would reject the operator's push as a disturbance — an
//      inference: the document's −5 N "force command of the human operator" was known to its
//      controller);
//   2. each axis's observer turns the scene's force F_T_W into u_i = F_i + F̂_d,i;
//   3. the motors get τ = Jᵀ u, saturated at max_joint_torque;
//   4. each observer is updated with the force that torque puts on the end effector,
//      (J^{-T} τ_sat)_i + F_h,i.
// Below the observer's cut-off the tool therefore moves as M̄ ẍ + B̄ ẋ = F + F_h on each axis
// (eq. 5), whatever the pose. The z component of the scene's force has nothing to act on.

#include <array>

#include "engine/control/disturbance_observer.hpp"
#include "engine/device/parallel_2dof.hpp"
#include "runtime/device_model.hpp"

namespace haptic::runtime {

class ParallelDobModel final : public DeviceModel {
 public:
  /// `plant`, `observer`: validated parameters; observer.sample_period is the loop period.
  /// `reachable_p_WT`: any pose the mechanism reaches (the device's initial one). Unit: m.
  /// `observer_enabled` false gives the bare coupled device (τ = Jᵀ F), for comparison.
  ParallelDobModel(const engine::Parallel2DofParams& plant,
                   const engine::DisturbanceObserverParams& observer,
                   const engine::Vec3& reachable_p_WT, bool observer_enabled = true);

  void estimate(const DeviceReading& reading, double dt, bool first, JointState& joints) override;
  void kinematics(const JointState& joints, ToolReading& tool) override;
  /// kError, with the zero command, for a non-finite force or a dt other than the observer's period.
  DeviceStatus joint_command(const ToolCommand& command, const DeviceReading& reading,
                             const JointState& joints, double dt, DeviceCommand& out) override;

  /// The observers' last estimates F̂_d (x, y), N; zero when disabled.
  engine::Vec3 disturbance_estimate() const;

 private:
  engine::Parallel2DofPlant kinematics_;  // its kinematics only (the state is not used)
  std::array<engine::DisturbanceObserver, 2> observers_;
  bool observer_enabled_;
  double period_;  // Unit: s.
  engine::parallel_2dof::Matrix2 G_;  // ∂q/∂x at the last kinematics. Unit: rad/m.
  engine::Vec3 v_WT_;                 // the end effector's velocity then. Unit: m/s.
};

}  // namespace haptic::runtime
