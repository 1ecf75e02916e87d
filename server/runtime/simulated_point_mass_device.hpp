#pragma once
// The default device: the 3-DOF point-mass plant (engine/device) held by a simulated operator
// (engine/operator). Its joints are the tool point's axes x, y, z of W (m), measured exactly with
// their rates (CartesianModel is its model). The operator's input is changed off the loop
// (SetOperator RPC) through a lock-free mailbox; its profiles and trajectories run on the device's
// own (simulated) clock from the tick the input arrives, so lockstep runs stay exactly reproducible.

#include "engine/device/point_mass_plant.hpp"
#include "engine/operator/simulated_hand.hpp"
#include "runtime/simulated_device.hpp"

namespace haptic::runtime {

class SimulatedPointMassDevice final : public SimulatedDevice {
 public:
  SimulatedPointMassDevice(const engine::PointMassParams& params,
                           const engine::PointMassState& initial, double max_force);

  DeviceStatus read(DeviceReading& reading) override;
  /// tau[0..2]: the force on the tool along x, y, z of W. Unit: N.
  DeviceStatus write(const DeviceCommand& command, double dt) override;

  std::uint32_t plant_joints(JointVector& q, JointVector& q_dot) const override;

  const engine::PointMassPlant& plant() const { return plant_; }

 private:
  engine::PointMassPlant plant_;
};

}  // namespace haptic::runtime
