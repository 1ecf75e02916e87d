#include "runtime/simulated_joystick_device.hpp"

#include <cassert>
#include <cmath>
#include <sstream>

namespace haptic::runtime {
namespace {

std::string bad(const char* name, const char* requirement, double value) {
  std::ostringstream out;
  out << name << ": " << requirement << ", got " << value;
  return out.str();
}

bool positive(double v) { return std::isfinite(v) && v > 0.0; }

}  // namespace

std::string SimulatedJoystickConfig::validate() const {
  if (const std::string message = params.validate(); !message.empty()) return "params." + message;
  if (integration.substeps < 1) return bad("integration.substeps", "must be >= 1", 0.0);
  if (!(std::isfinite(initial.theta) && std::abs(initial.theta) <= params.gimbal_limit)) {
    return bad("initial.theta", "must be within +-gimbal_limit", initial.theta);
  }
  if (!(std::isfinite(initial.phi) && std::abs(initial.phi) <= params.gimbal_limit)) {
    return bad("initial.phi", "must be within +-gimbal_limit", initial.phi);
  }
  if (!(std::isfinite(initial.R) && initial.R >= params.R_min && initial.R <= params.R_max)) {
    return bad("initial.R", "must be in [R_min, R_max]", initial.R);
  }
  if (!positive(watchdog.gimbal_rate)) return bad("watchdog.gimbal_rate", "must be finite and > 0", watchdog.gimbal_rate);
  if (!positive(watchdog.shaft_speed)) return bad("watchdog.shaft_speed", "must be finite and > 0", watchdog.shaft_speed);
  if (!positive(rule_stick_velocity)) {
    return bad("rule_stick_velocity", "must be finite and > 0", rule_stick_velocity);
  }
  if (!positive(max_force)) return bad("max_force", "must be finite and > 0", max_force);
  if (!(std::isfinite(rearm_after_s) && rearm_after_s >= 0.0)) {
    return bad("rearm_after_s", "must be finite and >= 0", rearm_after_s);
  }
  return {};
}

SimulatedJoystickDevice::SimulatedJoystickDevice(const SimulatedJoystickConfig& config)
    : config_(config),
      plant_(config.params, config.integration, config.initial),
      watchdog_(config.watchdog) {
  assert(config.validate().empty());
  const engine::GimbalJoystickParams& p = config.params;
  description_.name =
      "simulated 3-DOF gimbal joystick with motors and magnetic-particle brakes (004)";
  description_.model = "joystick_004";
  description_.capabilities.gravity = false;
  description_.capabilities.brakes = true;
  description_.capabilities.friction = true;
  description_.dof = 3;
  // The handle's bounding box over |θ|, |Φ| ≤ gimbal limit g and R in [R_min, R_max] (eq. 3.3):
  // |x|, |y| peak at the other angle zero (R_max sin g); z is least at both angles ±g.
  const double sg = std::sin(p.gimbal_limit), cg = std::cos(p.gimbal_limit);
  const double xy = p.R_max * sg;
  description_.workspace_min = {-xy, -xy, p.R_min * cg * cg / std::sqrt(1.0 - sg * sg * sg * sg)};
  description_.workspace_max = {xy, xy, p.R_max};
  description_.max_force = config.max_force;
  description_.simulated = true;
}

DeviceStatus SimulatedJoystickDevice::start() {
  // At power-up motors and brakes are at zero (L1773–L1776: motor DAC 2048, brake DAC 3900).
  command_ = {};
  return state_finite() ? DeviceStatus::kOk : DeviceStatus::kError;
}

void SimulatedJoystickDevice::stop() { command_ = {}; }

bool SimulatedJoystickDevice::state_finite() const {
  for (const double v : plant_.state()) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

void SimulatedJoystickDevice::fill_safe_command() {
  for (std::size_t i = 0; i < 3; ++i) {
    command_.motor[i] = 0.0;
    command_.brake[i] = config_.params.brake_limit(i);
  }
}

void SimulatedJoystickDevice::enter_safe_state() {
  safe_ = true;
  fill_safe_command();
}

bool SimulatedJoystickDevice::rearm() {
  if (!state_finite()) return false;
  watchdog_.rearm();
  safe_ = false;
  command_ = {};  // the original releases the brakes on the button press (L1955)
  return true;
}

void SimulatedJoystickDevice::check_watchdog() {
  const engine::Vec3 rates = plant_.measured_joint_rates();
  // Tachometers: θ̇, Φ̇ in rad/s and the shaft in m/s (Ṙ = r Ψ̇).
  if (watchdog_.check(rates.x, rates.y, config_.params.r * rates.z) && !safe_) enter_safe_state();
}

DeviceStatus SimulatedJoystickDevice::read(DeviceReading& reading) {
  const engine::GimbalJoystickParams& p = config_.params;
  const engine::Vec3 q = plant_.measured_joints();
  const engine::Vec3 q_dot = plant_.measured_joint_rates();
  reading.p_WT = engine::joystick_forward({q.x, q.y, p.r * q.z});
  reading.v_WT = engine::joystick_multiply(engine::joystick_jacobian(q.x, q.y, q.z, p.r), q_dot);
  if (!state_finite() || !engine::is_finite(reading.p_WT) || !engine::is_finite(reading.v_WT)) {
    enter_safe_state();
    return DeviceStatus::kError;
  }
  check_watchdog();
  reading.safe_state = safe_;
  return DeviceStatus::kOk;
}

void SimulatedJoystickDevice::rearm_when_at_rest(double dt) {
  if (!safe_ || config_.rearm_after_s <= 0.0) {
    at_rest_s_ = 0.0;
    return;
  }
  const engine::Vec3 rates = plant_.measured_joint_rates();
  const engine::JoystickWatchdogLimits& limits = config_.watchdog;
  const bool still = std::abs(rates.x) < 0.1 * limits.gimbal_rate &&
                     std::abs(rates.y) < 0.1 * limits.gimbal_rate &&
                     std::abs(config_.params.r * rates.z) < 0.1 * limits.shaft_speed;
  at_rest_s_ = still ? at_rest_s_ + dt : 0.0;
  if (at_rest_s_ >= config_.rearm_after_s && rearm()) at_rest_s_ = 0.0;
}

DeviceStatus SimulatedJoystickDevice::write(const DeviceCommand& command, double dt) {
  double t = 0.0;
  const engine::HandInput& hand = hand_.begin_tick(t);
  const engine::GimbalJoystickParams& p = config_.params;
  // A NaN is a fault: brakes on at once, and the write reports the error like every device's.
  const bool command_ok = engine::is_finite(command.F_T_W);
  if (!safe_ && !command_ok) enter_safe_state();
  if (safe_) {
    fill_safe_command();
  } else {
    const engine::Vec3 q = plant_.measured_joints();
    const engine::Vec3 q_dot = plant_.measured_joint_rates();
    const engine::JoystickMatrix J = engine::joystick_jacobian(q.x, q.y, q.z, p.r);
    const engine::Vec3 tau = engine::joystick_multiply_transposed(J, command.F_T_W);  // eq. 3.18
    // The load cell's view of the hand at the start of the tick, as joint torques (eq. 3.20).
    engine::Vec3 p_WT, v_WT;
    plant_.handle_state(plant_.state(), p_WT, v_WT);
    const engine::Vec3 tau_user =
        engine::joystick_multiply_transposed(J, engine::hand_force(hand, p_WT, v_WT, t));
    const double taus[3] = {tau.x, tau.y, tau.z};
    const double rates[3] = {q_dot.x, q_dot.y, q_dot.z};
    const double users[3] = {tau_user.x, tau_user.y, tau_user.z};
    for (std::size_t i = 0; i < 3; ++i) {
      const engine::HybridRuleParams rule{p.brake_limit(i), config_.rule_stick_velocity};
      const engine::HybridSplit split = engine::split_hybrid(taus[i], rates[i], users[i], rule);
      command_.motor[i] = engine::saturate(split.motor, p.motor_limit(i));
      command_.brake[i] = split.brake;
    }
  }
  plant_.step(
      command_, dt,
      [&](const engine::Vec3& p_handle, const engine::Vec3& v_handle) {
        return engine::hand_force(hand, p_handle, v_handle, t);
      },
      engine::hand_mass(hand));
  hand_.end_tick(dt);
  if (!state_finite()) {
    enter_safe_state();
    return DeviceStatus::kError;
  }
  check_watchdog();
  rearm_when_at_rest(dt);
  return command_ok ? DeviceStatus::kOk : DeviceStatus::kError;
}

}  // namespace haptic::runtime
