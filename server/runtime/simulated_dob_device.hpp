#pragma once
// Document 001's device as a simulated device: the 2-DOF parallel mechanism of
// engine/device/parallel_2dof, held by the simulated operator at its end effector. ParallelDobModel
// (kinematics, Jᵀ and the disturbance observers) is its model.
//
// Its joints are the motor angles q = (q_1, q_2) and their rates (encoders and tachometers, exact);
// its handle carries a force sensor that reads the operator's force at the start of each tick
// (DeviceReading::F_sensor_W, z = 0). The command is the motors' torques (N·m), saturated at
// max_joint_torque and held over the tick; the operator's force is re-evaluated at every
// integration stage. A hand that follows a target adds its mass to the end effector (the observer,
// seeing it as a disturbance, hides it below the cut-off: a limitation of the simulated sensor,
// which measures only the hand's spring-damper force).

#include <cstdint>

#include "engine/device/parallel_2dof.hpp"
#include "runtime/simulated_device.hpp"

namespace haptic::runtime {

class SimulatedDobDevice final : public SimulatedDevice {
 public:
  /// `plant`: validated parameters. `initial_p_WT`: the end effector's start, reachable (z
  /// ignored). Unit: m. `max_force`: reported to the loop's force guard. Unit: N.
  /// `observer_enabled`: what the description says of the model it runs with.
  SimulatedDobDevice(const engine::Parallel2DofParams& plant, const engine::Vec3& initial_p_WT,
                     double max_force, bool observer_enabled = true,
                     double nominal_mass = 0.0, double nominal_damping = 0.0);

  /// kError when the state is not finite (a NaN, or the end effector out of reach).
  DeviceStatus read(DeviceReading& reading) override;
  /// kError, without advancing, for a non-finite torque or state.
  DeviceStatus write(const DeviceCommand& command, double dt) override;

  /// The motor angles and rates (rad, rad/s).
  std::uint32_t plant_joints(JointVector& q, JointVector& q_dot) const override;

  const engine::Parallel2DofPlant& plant() const { return plant_; }
  /// The operator's force the handle sensor read on the last tick, in W. Unit: N.
  const engine::Vec3& measured_hand_force() const { return hand_force_; }

 private:
  engine::Parallel2DofPlant plant_;
  engine::Vec3 hand_force_;
};

}  // namespace haptic::runtime
