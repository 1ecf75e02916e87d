#pragma once
// Document 000's 1-DOF device as a simulated device: DC motor + gearbox + link under gravity
// (engine/device/dc_motor_plant), held at its end point E by the simulated operator. Its joint is
// the motor shaft, read exactly with its rate (θ_m, θ̇_m; rad, rad/s); the command is the motor
// torque τ_m (N·m), which an ideal current amplifier gives as the voltage u_m = (R_m / k_m) τ_m
// (eq. 2.6 at steady current). DcMotorModel is its model. The simulated hand's mass is not
// modelled on this device: the link's inertia dominates.

#include <cstdint>

#include "engine/device/dc_motor_plant.hpp"
#include "runtime/simulated_device.hpp"

namespace haptic::runtime {

class SimulatedDcMotorDevice final : public SimulatedDevice {
 public:
  /// `initial_theta_L`: the load angle at start. Unit: rad. `max_force`: at the tool. Unit: N.
  SimulatedDcMotorDevice(const engine::DcMotorParams& params, engine::DcMotorModel model,
                         double initial_theta_L, double max_force,
                         engine::IntegrationSettings integration);

  DeviceStatus read(DeviceReading& reading) override;
  DeviceStatus write(const DeviceCommand& command, double dt) override;

  /// The load angle θ_L = r θ_m and its rate (000 eq. 3.1a). Units: rad, rad/s.
  std::uint32_t plant_joints(JointVector& q, JointVector& q_dot) const override;

  const engine::DcMotorPlant& plant() const { return plant_; }

 private:
  engine::DcMotorPlant plant_;
};

}  // namespace haptic::runtime
