#include "runtime/simulated_joystick_device.hpp"

#include <cassert>
#include <algorithm>
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
      plant_(config.params, config.integration, config.initial) {
  assert(config.validate().empty());
  const engine::GimbalJoystickParams& p = config.params;
  description_.name =
      "simulated 3-DOF gimbal joystick with motors and magnetic-particle brakes (004)";
  description_.model = "joystick_004";
  description_.capabilities.gravity = false;
  description_.capabilities.brakes = true;
  description_.capabilities.friction = true;
  description_.capabilities.measured_rates = true;
  description_.dof = 3;
  description_.joints = 3;
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

void SimulatedJoystickDevice::enter_safe_state() { fill_safe_command(); }

std::uint32_t SimulatedJoystickDevice::plant_joints(JointVector& q, JointVector& q_dot) const {
  namespace js = engine::joystick_state;
  const engine::JoystickState& x = plant_.state();
  q[0] = x[js::kTheta];
  q[1] = x[js::kPhi];
  q[2] = x[js::kR];
  q_dot[0] = x[js::kThetaDot];
  q_dot[1] = x[js::kPhiDot];
  q_dot[2] = x[js::kRDot];
  return 3;
}

std::optional<JointSpaceDynamics> SimulatedJoystickDevice::joint_space_dynamics() const {
  namespace js = engine::joystick_state;
  const engine::GimbalJoystickParams& p = plant_.params();
  const engine::JoystickState& x = plant_.state();
  JointSpaceDynamics out;
  out.inertia[0][0] = p.I_theta;
  out.inertia[1][1] = p.I_phi;
  out.inertia[2][2] = p.M_m + p.M_s;
  out.jacobian = engine::joystick_jacobian_R(x[js::kTheta], x[js::kPhi], x[js::kR]);
  return out;
}

DeviceStatus SimulatedJoystickDevice::read(DeviceReading& reading) {
  if (!state_finite()) {
    fill_safe_command();
    return DeviceStatus::kError;
  }
  const engine::Vec3 q = plant_.measured_joints();
  const engine::Vec3 q_dot = plant_.measured_joint_rates();
  reading.q[0] = q.x;
  reading.q[1] = q.y;
  reading.q[2] = q.z;
  reading.q_dot[0] = q_dot.x;
  reading.q_dot[1] = q_dot.y;
  reading.q_dot[2] = q_dot.z;
  // The load cell: the hand's force on the handle at the start of the tick.
  double t = 0.0;
  const engine::HandInput& hand = hand_.begin_tick(t);
  engine::Vec3 p_WT, v_WT;
  plant_.handle_state(plant_.state(), p_WT, v_WT);
  reading.F_sensor_W = engine::hand_force(hand, p_WT, v_WT, t);
  return DeviceStatus::kOk;
}

DeviceStatus SimulatedJoystickDevice::write(const DeviceCommand& command, double dt) {
  double t = 0.0;
  const engine::HandInput& hand = hand_.begin_tick(t);
  const engine::GimbalJoystickParams& p = config_.params;
  bool command_ok = true;
  for (std::size_t i = 0; i < 3; ++i) {
    command_ok = command_ok && std::isfinite(command.tau[i]) && std::isfinite(command.brake[i]);
  }
  if (command_ok) {
    for (std::size_t i = 0; i < 3; ++i) {
      command_.motor[i] = command.tau[i];
      command_.brake[i] = std::clamp(command.brake[i], 0.0, p.brake_limit(i));
    }
  } else {
    fill_safe_command();  // a NaN is a fault: brakes on for this tick
  }
  plant_.step(
      command_, dt,
      [&](const engine::Vec3& p_handle, const engine::Vec3& v_handle) {
        return engine::hand_force(hand, p_handle, v_handle, t);
      },
      engine::hand_mass(hand));
  hand_.end_tick(dt);
  if (!state_finite()) {
    fill_safe_command();
    return DeviceStatus::kError;
  }
  return command_ok ? DeviceStatus::kOk : DeviceStatus::kError;
}

}  // namespace haptic::runtime
