#pragma once
// Document 004's joystick (Russo 1990) as a simulated device: two gimbal rings and a cable-driven
// shaft, a motor and a magnetic-particle brake on every axis (engine/device/gimbal_joystick),
// held at the handle by the simulated operator. JoystickModel (kinematics, Jᵀ, the brake rule and
// the watchdog) is its model.
//
// The reading is what the sensors give: encoders and tachometers on the drive shafts (θ, Φ, Ψ;
// rad, rad/s) and the handle's load cell (the hand's force at the start of the tick, in W). The
// command is the motors' torques and the brakes' clamping torques (N·m), held over the tick; a
// non-finite command, or enter_safe_state(), gives that tick motors zero and brakes at their
// limits. read() returns kError while the state is non-finite.

#include <array>
#include <cstdint>

#include "engine/core/integrator.hpp"
#include "engine/device/gimbal_joystick.hpp"
#include "engine/operator/simulated_hand.hpp"
#include "runtime/joystick_model.hpp"
#include "runtime/simulated_device.hpp"

namespace haptic::runtime {

struct SimulatedJoystickConfig {
  engine::GimbalJoystickParams params;
  engine::IntegrationSettings integration{engine::Integrator::kRk4, 10};
  engine::JoystickPose initial{0.0, 0.0, 0.24};  // Unit: rad, rad, m (mid-stroke).
  engine::JoystickWatchdogLimits watchdog;
  /// See JoystickModelParams. Unit: rad/s.
  double rule_stick_velocity = 1e-3;
  /// Force at the tool the scene may ask for. Unit: N. [I] the motors' limit at mid-stroke R:
  /// 1.78 N·m / 0.24 m ≈ 7.4 N.
  double max_force = 7.0;
  /// See JoystickModelParams. Unit: s.
  double rearm_after_s = 1.0;
  /// See JoystickModelParams.
  bool brakes_released = false;

  /// Empty when usable; otherwise one message naming the bad field ("params.M_s: …").
  std::string validate() const;
  /// The model's part.
  JoystickModelParams model() const {
    return {params, watchdog, rule_stick_velocity, rearm_after_s, brakes_released};
  }
};

class SimulatedJoystickDevice final : public SimulatedDevice {
 public:
  /// `config` must validate.
  explicit SimulatedJoystickDevice(const SimulatedJoystickConfig& config);

  DeviceStatus start() override;
  void stop() override;
  DeviceStatus read(DeviceReading& reading) override;
  /// tau: the motors' torques; brake: the brakes' (clamped into [0, limit]). Units: N·m.
  DeviceStatus write(const DeviceCommand& command, double dt) override;
  /// Motors to zero and brakes to their limits until the next write. On the loop: no allocation.
  void enter_safe_state() override;

  /// θ, Φ (rad) and the shaft R (m), with their rates: the load side, not the encoders'.
  std::uint32_t plant_joints(JointVector& q, JointVector& q_dot) const override;
  /// Over (θ, Φ, R): eq. 3.27's diagonal inertia (I_θ, I_Φ) and the shaft's motor and load sides
  /// taken as one rigid body, M_m + M_s (L935; the sum that puts eq. 4.5's breakpoint at 41 rad/s,
  /// L940) — the cable's own mode, √(k_t (1/M_m + 1/M_s)) ≈ 1000 rad/s, is not modelled here —
  /// through ∂x/∂(θ, Φ, R) of eq. 3.13. The plant has no viscous friction (Coulomb friction and
  /// brakes only, which Colgate's bound does not credit), so the damping is 0.
  std::optional<JointSpaceDynamics> joint_space_dynamics() const override;

  /// The commands applied with the last write. Units: N·m.
  const engine::JoystickActuatorCommand& last_command() const { return command_; }
  const engine::GimbalJoystickPlant& plant() const { return plant_; }

 private:
  bool state_finite() const;
  void fill_safe_command();

  SimulatedJoystickConfig config_;
  engine::GimbalJoystickPlant plant_;
  engine::JoystickActuatorCommand command_{};
};

}  // namespace haptic::runtime
