#pragma once
// The default device: the 3-DOF point-mass plant (engine/device) held by a simulated operator
// (engine/operator). Its joints are the tool point's axes x, y, z of W (m), measured exactly with
// their rates (CartesianModel is its model). The operator's input is changed off the loop
// (SetOperator RPC) through a lock-free mailbox; its profiles and trajectories run on the device's
// own (simulated) clock from the tick the input arrives, so lockstep runs stay exactly reproducible.
//
// With a rotation it is the 6-DOF device: the handle is also a rigid body turning about the tool
// point (engine/device/rigid_body_rotation), its orientation and angular velocity measured
// exactly, taking torques (capabilities.orientation and torque). The simulated hand grips the
// position only: the handle turns under the device's torque alone.

#include <optional>

#include "engine/device/point_mass_plant.hpp"
#include "engine/device/position_sensor.hpp"
#include "engine/device/rigid_body_rotation.hpp"
#include "engine/operator/simulated_hand.hpp"
#include "runtime/simulated_device.hpp"

namespace haptic::runtime {

/// The handle's rotation of the 6-DOF device.
struct SimulatedRotation {
  engine::RotationParams params;
  engine::RotationState initial;
  double max_torque = 0.2;  // Unit: N·m. > 0.
};

class SimulatedPointMassDevice final : public SimulatedDevice {
 public:
  /// sensor: the position measured with noise and quantization, the velocity its backward
  /// difference (docs/identification.md); none: both exactly.
  SimulatedPointMassDevice(const engine::PointMassParams& params,
                           const engine::PointMassState& initial, double max_force,
                           const std::optional<SimulatedRotation>& rotation = std::nullopt,
                           const std::optional<engine::PositionSensorParams>& sensor = std::nullopt);

  DeviceStatus read(DeviceReading& reading) override;
  /// tau[0..2]: the force on the tool along x, y, z of W (N); tau_W the torque on the handle
  /// (N·m; the 6-DOF device only).
  DeviceStatus write(const DeviceCommand& command, double dt) override;

  std::uint32_t plant_joints(JointVector& q, JointVector& q_dot) const override;

  const engine::PointMassPlant& plant() const { return plant_; }
  /// The handle's rotation (the 6-DOF device), else null.
  const engine::RigidBodyRotation* rotation() const { return rotation_ ? &*rotation_ : nullptr; }

 private:
  engine::PointMassPlant plant_;
  std::optional<engine::RigidBodyRotation> rotation_;
  std::optional<engine::PositionSensor> sensor_;
  double last_period_s_ = 0.0;  // the last write's tick: the sensor's difference quotient's
};

}  // namespace haptic::runtime
