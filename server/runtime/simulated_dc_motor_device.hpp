#pragma once
// Document 000's 1-DOF device as a hapticd device: DC motor + gearbox + link under gravity
// (engine/device/dc_motor_plant), held at its end point E by the simulated operator.
//
// The tool point T is the link's end point E, which moves on a circle of radius l in the device's
// x–y plane (y up, z the joint axis): p_WT = l (cos φ, sin φ, 0), φ = θ_L + α_c, θ_L = r θ_m
// (eqs. 3.1a, 4.2a). The scene's force F on the tool becomes the load torque τ_d = Jᵀ F
// (eqs. 4.1–4.3), commanded through the motor voltage with gravity compensation and nothing else:
//   (k_m/R_m) u_m = (r/η)(τ_g(θ_m) + τ_d)          (direct torque control 5.2 with 6.7's τ_g term)
// so the link moves as J_eff θ̈_m + B θ̇_m = (r/η)(τ_d + τ_e): the motor's own damping B (with the
// back-EMF) stays, which keeps the device passive. The operator's force enters as τ_e (4.6).
// Only the force component along the circle's tangent can act on a 1-DOF link.

#include <cstdint>

#include "engine/device/dc_motor_plant.hpp"
#include "engine/operator/simulated_hand.hpp"
#include "runtime/device.hpp"
#include "runtime/simulated_operator.hpp"

namespace haptic::runtime {

class SimulatedDcMotorDevice final : public Device {
 public:
  /// `initial_theta_L`: the load angle at start. Unit: rad. `max_force`: at the tool. Unit: N.
  SimulatedDcMotorDevice(const engine::DcMotorParams& params, engine::DcMotorModel model,
                         double initial_theta_L, double max_force,
                         engine::IntegrationSettings integration);

  const DeviceDescription& description() const override { return description_; }
  DeviceStatus start() override { return DeviceStatus::kOk; }
  void stop() override {}
  DeviceStatus read(DeviceReading& reading) override;
  DeviceStatus write(const DeviceCommand& command, double dt) override;

  /// Off the loop: what the simulated hand does from the next tick on (its mass is not modelled
  /// on this device: the link's inertia dominates).
  void set_hand(const engine::HandInput& input) { hand_.set(input); }

  const engine::DcMotorPlant& plant() const { return plant_; }

 private:
  /// Tool position and velocity for a motor state.
  void tool_state(double theta_m, double omega_m, engine::Vec3& p_WT, engine::Vec3& v_WT) const;

  DeviceDescription description_;
  engine::DcMotorPlant plant_;
  SimulatedOperator hand_;
};

}  // namespace haptic::runtime
