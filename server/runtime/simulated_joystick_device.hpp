#pragma once
// Document 004's joystick (Russo 1990) as a hapticd device: two gimbal rings and a cable-driven
// shaft, a motor and a magnetic-particle brake on every axis (engine/device/gimbal_joystick),
// held at the handle by the simulated operator.
//
// Frames: W has its origin at the gimbal centre and z along the shaft at θ = Φ = 0 (eq. 3.1); the
// tool point T is the handle, p_WT = R n_s(θ, Φ) (eq. 3.3). The reading is what the sensors give:
// encoders and tachometers on the drive shafts (θ, Φ, Ψ), so R = r Ψ is the motor side of the
// cable — the handle differs from it by the cable stretch (≤ 0.883 N·m / r / k_t ≈ 1.1 mm).
//
// A command F_T_W becomes joint torques τ = Jᵀ F (eq. 3.18, J at the measured joints), split per
// axis by the hybrid power rule (engine/control/brake_rule: brakes take what flows in, motors
// what flows out; near rest the hand's force on the handle, as the load cell would measure it,
// decides). The hand's force for that decision is the one at the start of the tick.
// Safety (L510, L1930): the watchdog checks the tachometers every tick; a trip, a non-finite state
// or enter_safe_state() puts the device in its safe state — motors zero, brakes at their limits —
// until rearm(). read() returns kError while the state is non-finite.

#include <array>
#include <cstdint>

#include "engine/control/brake_rule.hpp"
#include "engine/control/joystick_watchdog.hpp"
#include "engine/core/integrator.hpp"
#include "engine/device/gimbal_joystick.hpp"
#include "engine/operator/simulated_hand.hpp"
#include "runtime/device.hpp"
#include "runtime/simulated_operator.hpp"

namespace haptic::runtime {

struct SimulatedJoystickConfig {
  engine::GimbalJoystickParams params;
  engine::IntegrationSettings integration{engine::Integrator::kRk4, 10};
  engine::JoystickPose initial{0.0, 0.0, 0.24};  // Unit: rad, rad, m (mid-stroke).
  engine::JoystickWatchdogLimits watchdog;
  /// Below this joint speed the hand's force decides motor or brake. Unit: rad/s (Ψ: rad/s of the
  /// drive pulley; 1e-3 rad/s there is ≈ 10 µm/s of shaft).
  double rule_stick_velocity = 1e-3;
  /// Force at the tool the scene may ask for. Unit: N. [I] the motors' limit at mid-stroke R:
  /// 1.78 N·m / 0.24 m ≈ 7.4 N.
  double max_force = 7.0;
  /// After a trip, re-arm once every axis has stayed below a tenth of its watchdog limit for this
  /// long — the simulated operator's press of the re-arm button (L1955). 0: never (re-arm()
  /// only). Unit: s.
  double rearm_after_s = 1.0;

  /// Empty when usable; otherwise one message naming the bad field ("params.M_s: …").
  std::string validate() const;
};

class SimulatedJoystickDevice final : public Device {
 public:
  /// `config` must validate.
  explicit SimulatedJoystickDevice(const SimulatedJoystickConfig& config);

  const DeviceDescription& description() const override { return description_; }
  DeviceStatus start() override;
  void stop() override;
  DeviceStatus read(DeviceReading& reading) override;
  DeviceStatus write(const DeviceCommand& command, double dt) override;

  /// Motors to zero and brakes to their limits, from now until rearm() (the server calls this on
  /// any device fault). On the loop: no allocation.
  void enter_safe_state() override;
  /// Leaves the safe state and clears the watchdog (the original's button press, L1951); refused
  /// (returns false) while the state is non-finite.
  bool rearm();
  bool in_safe_state() const { return safe_; }
  bool watchdog_tripped() const { return watchdog_.tripped(); }

  /// Off the loop: what the simulated hand does from the next tick on.
  void set_hand(const engine::HandInput& input) { hand_.set(input); }

  /// The commands sent with the last write (after the rule and the safe state). Units: N·m.
  const engine::JoystickActuatorCommand& last_command() const { return command_; }
  const engine::GimbalJoystickPlant& plant() const { return plant_; }

 private:
  bool state_finite() const;
  /// Runs the watchdog on the tachometers; trips into the safe state.
  void check_watchdog();
  void fill_safe_command();
  void rearm_when_at_rest(double dt);

  SimulatedJoystickConfig config_;
  DeviceDescription description_;
  engine::GimbalJoystickPlant plant_;
  engine::JoystickWatchdog watchdog_;
  SimulatedOperator hand_;
  engine::JoystickActuatorCommand command_{};
  bool safe_ = false;
  double at_rest_s_ = 0.0;  // time in the safe state with every axis nearly still. Unit: s.
};

}  // namespace haptic::runtime
