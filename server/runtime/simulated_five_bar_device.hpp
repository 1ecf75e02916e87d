#pragma once
// Document 003's five-bar (Madill 1998; engine/device/five_bar) as a simulated device, held at its
// tip by the simulated operator. FiveBarModel (kinematics, Jᵀ, velocity estimation) is its model.
//
// The reading is what the hardware would see: the joint angles from the encoders (Table 5.2 with
// the axial −π/6000, counted from the home pose; switchable), no tachometers, and the operator's
// joint torques Jᵀ(q) F_hand as the strain gauges measure them (DeviceReading::tau_sensor, for a
// state estimator). The command is the joint torques (N·m), saturated per joint at the D/A limit
// (L3237) by the plant. The operator's force acts at the tip through Jᵀ, and a gripping hand's
// mass moves with the tip.
//
// With options.plant.flexible_mode link 5 carries one horizontal bending mode (engine
// FiveBarFlexibleMode) and capabilities.flexible_modes is set. The hand then holds the physical,
// deflected tip p_rigid(q) + φ1(l) η n(q0), but the encoders measure only the joints, so the
// model's tool point is the rigid tip of the measured joints and does not see the deflection (the
// thesis' strain gauge at the clamp, eq. 3.115, would; it is not simulated).
// plant().physical_tip_state() gives the deflected tip.

#include <array>
#include <cstdint>
#include <random>

#include "engine/device/five_bar.hpp"
#include "runtime/simulated_device.hpp"

namespace haptic::runtime {

struct SimulatedFiveBarOptions {
  engine::FiveBarPlantOptions plant;  // RK4 × 10 sub-steps, Coriolis on, rigid link 5.
  bool quantized = true;              // Read the angles through the encoders.
  double velocity_cutoff = 20.0;      // ω0 of the model's velocity low-pass (L3193). Unit: rad/s.
  /// Largest tool force the server may command: ≈ the smallest joint limit over the 0.6 m arm
  /// (7.22 N·m / 0.6 m). Unit: N.
  double max_force = 12.0;
  /// The model runs a state estimator (capabilities.state_estimator).
  bool state_estimator = false;
  /// Gaussian noise on each joint's angle before the encoders count it (rms; 0: none), drawn
  /// from `noise_seed`: an encoder's count flickers where the angle sits near a step. Unit: rad.
  std::array<double, 3> encoder_noise{};
  std::uint64_t noise_seed = 0;
};

class SimulatedFiveBarDevice final : public SimulatedDevice {
 public:
  SimulatedFiveBarDevice(const engine::FiveBarParams& params,
                         const engine::FiveBarState& initial = {},
                         const SimulatedFiveBarOptions& options = {});

  DeviceStatus read(DeviceReading& reading) override;
  DeviceStatus write(const DeviceCommand& command, double dt) override;

  /// The true joint angles and rates (rad, rad/s).
  std::uint32_t plant_joints(JointVector& q, JointVector& q_dot) const override;
  /// D(q) of eq. 4.10 with the hub inertia (FiveBarPlant::mass_matrix), Table 5.4's viscous B per
  /// joint, J(q) of eq. 3.120, at the plant's state.
  std::optional<JointSpaceDynamics> joint_space_dynamics() const override;

  const engine::FiveBarPlant& plant() const { return plant_; }
  /// Off the loop (tests, resets): replaces the plant state and puts the flexible mode at rest
  /// (restart the model's estimation too: DevicePort::restart_estimation).
  void set_plant_state(const engine::FiveBarState& state);
  /// The joint angles as last measured. Unit: rad.
  const engine::FiveBarJoints& measured_joints() const { return q_measured_; }

 private:
  engine::FiveBarJoints measure(const engine::FiveBarJoints& q);
  bool state_finite() const;

  SimulatedFiveBarOptions options_;
  engine::FiveBarPlant plant_;
  engine::FiveBarJoints q_measured_{};  // Unit: rad.
  std::mt19937_64 noise_random_;
  std::normal_distribution<double> unit_noise_{0.0, 1.0};
};

}  // namespace haptic::runtime
