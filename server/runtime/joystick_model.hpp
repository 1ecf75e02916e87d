#pragma once
// Document 004's joystick (Russo 1990) as the loop models it: two gimbal rings and a cable-driven
// shaft, a motor and a magnetic-particle brake on every axis (engine/device/gimbal_joystick).
//
// Frames: W has its origin at the gimbal centre and z along the shaft at θ = Φ = 0 (eq. 3.1); the
// tool point T is the handle, p_WT = R n_s(θ, Φ) (eq. 3.3). The joints are the drive shafts as
// the encoders and tachometers give them, (θ, Φ, Ψ) in rad with R = r Ψ the motor side of the
// cable (the handle differs from it by the cable stretch, ≤ 0.883 N·m / r / k_t ≈ 1.1 mm).
//
// A command F_T_W becomes joint torques τ = Jᵀ F (eq. 3.18, J at the measured joints), split per
// axis by the hybrid power rule (engine/control/brake_rule: brakes take what flows in, motors
// what flows out; near rest the hand's force on the handle, as the load cell measures it
// (DeviceReading::F_sensor_W), decides).
// Safety (L510, L1930): the watchdog checks the tachometers every tick; a trip, a device fault
// or a non-finite command puts the device in its safe state — motors zero, brakes at their
// limits — until rearm().

#include "engine/control/brake_rule.hpp"
#include "engine/control/joystick_watchdog.hpp"
#include "engine/device/gimbal_joystick.hpp"
#include "runtime/device_model.hpp"

namespace haptic::runtime {

struct JoystickModelParams {
  engine::GimbalJoystickParams params;
  engine::JoystickWatchdogLimits watchdog;
  /// Below this joint speed the hand's force decides motor or brake. Unit: rad/s (Ψ: rad/s of the
  /// drive pulley; 1e-3 rad/s there is ≈ 10 µm/s of shaft).
  double rule_stick_velocity = 1e-3;
  /// After a trip, re-arm once every axis has stayed below a tenth of its watchdog limit for this
  /// long — the simulated operator's press of the re-arm button (L1955). 0: never (rearm()
  /// only). Unit: s.
  double rearm_after_s = 1.0;
  /// The brakes stay released (at their residual) and the motors take the whole command, as far
  /// as they can: the mechanism alone, as it is identified on the bench, where a brake that takes
  /// the dissipating part of the excitation would hide its mass. The watchdog and the safe state
  /// still brake.
  bool brakes_released = false;
};

class JoystickModel final : public DeviceModel {
 public:
  explicit JoystickModel(const JoystickModelParams& params);

  void estimate(const DeviceReading& reading, double dt, bool first, JointState& joints) override;
  void kinematics(const JointState& joints, ToolReading& tool) override;
  bool holds_safe_state() const override { return safe_; }
  /// In the safe state, or for a non-finite force (which enters it; kError), the safe command.
  DeviceStatus joint_command(const ToolCommand& command, const DeviceReading& reading,
                             const JointState& joints, double dt, DeviceCommand& out) override;
  void safe_command(DeviceCommand& out) const override;
  /// Motors to zero and brakes to their limits, from now until rearm(); the device has faulted.
  void enter_safe_state() override;

  /// Leaves the safe state and clears the watchdog (the original's button press, L1951); refused
  /// (returns false) while the device's readings are failing.
  bool rearm();
  bool in_safe_state() const { return safe_; }
  bool watchdog_tripped() const { return watchdog_.tripped(); }

 private:
  void rearm_when_at_rest(const JointVector& q_dot, double dt);

  JoystickModelParams params_;
  engine::JoystickWatchdog watchdog_;
  engine::JoystickMatrix J_{};  // at the last kinematics
  bool safe_ = false;
  bool faulted_ = false;    // entered the safe state on a fault, with no good reading since
  double at_rest_s_ = 0.0;  // time in the safe state with every axis nearly still. Unit: s.
};

}  // namespace haptic::runtime
