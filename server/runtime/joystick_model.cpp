#include "runtime/joystick_model.hpp"

#include <cmath>

namespace haptic::runtime {

JoystickModel::JoystickModel(const JoystickModelParams& params)
    : params_(params), watchdog_(params.watchdog) {}

void JoystickModel::estimate(const DeviceReading& reading, double dt, bool first, JointState& joints) {
  joints.q = reading.q;
  joints.q_dot = reading.q_dot;  // tachometers
  faulted_ = false;
  // Tachometers: θ̇, Φ̇ in rad/s and the shaft in m/s (Ṙ = r Ψ̇).
  if (watchdog_.check(reading.q_dot[0], reading.q_dot[1], params_.params.r * reading.q_dot[2]) && !safe_) {
    safe_ = true;
  }
  if (!first) rearm_when_at_rest(reading.q_dot, dt);
}

void JoystickModel::kinematics(const JointState& joints, ToolReading& tool) {
  const double r = params_.params.r;
  const JointVector& q = joints.q;
  tool.p_WT = engine::joystick_forward({q[0], q[1], r * q[2]});
  J_ = engine::joystick_jacobian(q[0], q[1], q[2], r);
  tool.v_WT = engine::joystick_multiply(J_, {joints.q_dot[0], joints.q_dot[1], joints.q_dot[2]});
}

void JoystickModel::safe_command(DeviceCommand& out) const {
  out = {};
  for (std::size_t i = 0; i < 3; ++i) out.brake[i] = params_.params.brake_limit(i);
}

void JoystickModel::enter_safe_state() {
  safe_ = true;
  faulted_ = true;
}

bool JoystickModel::rearm() {
  if (faulted_) return false;
  watchdog_.rearm();
  safe_ = false;  // the original releases the brakes on the button press (L1955)
  at_rest_s_ = 0.0;
  return true;
}

void JoystickModel::rearm_when_at_rest(const JointVector& q_dot, double dt) {
  if (!safe_ || params_.rearm_after_s <= 0.0) {
    at_rest_s_ = 0.0;
    return;
  }
  const engine::JoystickWatchdogLimits& limits = params_.watchdog;
  const bool still = std::abs(q_dot[0]) < 0.1 * limits.gimbal_rate &&
                     std::abs(q_dot[1]) < 0.1 * limits.gimbal_rate &&
                     std::abs(params_.params.r * q_dot[2]) < 0.1 * limits.shaft_speed;
  at_rest_s_ = still ? at_rest_s_ + dt : 0.0;
  if (at_rest_s_ >= params_.rearm_after_s && rearm()) at_rest_s_ = 0.0;
}

DeviceStatus JoystickModel::joint_command(const ToolCommand& command, const DeviceReading& reading,
                                          const JointState& joints, double, DeviceCommand& out) {
  // A NaN is a fault: brakes on at once, and the command reports the error like every model's.
  const bool command_ok = engine::is_finite(command.F_T_W);
  if (!command_ok) safe_ = true;
  if (safe_) {
    safe_command(out);
    return command_ok ? DeviceStatus::kOk : DeviceStatus::kError;
  }
  const engine::GimbalJoystickParams& p = params_.params;
  const engine::Vec3 tau = engine::joystick_multiply_transposed(J_, command.F_T_W);  // eq. 3.18
  // The load cell's view of the hand at the start of the tick, as joint torques (eq. 3.20).
  const engine::Vec3 tau_user = engine::joystick_multiply_transposed(J_, reading.F_sensor_W);
  const double taus[3] = {tau.x, tau.y, tau.z};
  const double users[3] = {tau_user.x, tau_user.y, tau_user.z};
  out = {};
  for (std::size_t i = 0; i < 3; ++i) {
    if (params_.brakes_released) {
      out.tau[i] = engine::saturate(taus[i], p.motor_limit(i));
      continue;
    }
    const engine::HybridRuleParams rule{p.brake_limit(i), params_.rule_stick_velocity};
    const engine::HybridSplit split = engine::split_hybrid(taus[i], joints.q_dot[i], users[i], rule);
    out.tau[i] = engine::saturate(split.motor, p.motor_limit(i));
    out.brake[i] = split.brake;
  }
  return DeviceStatus::kOk;
}

}  // namespace haptic::runtime
