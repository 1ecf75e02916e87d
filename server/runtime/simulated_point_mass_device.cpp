#include "runtime/simulated_point_mass_device.hpp"

namespace haptic::runtime {

SimulatedPointMassDevice::SimulatedPointMassDevice(const engine::PointMassParams& params,
                                                   const engine::PointMassState& initial,
                                                   double max_force,
                                                   const std::optional<SimulatedRotation>& rotation,
                                                   const std::optional<engine::PositionSensorParams>& sensor)
    : plant_(params, initial) {
  if (sensor) sensor_.emplace(*sensor);
  description_.name = "simulated point mass (3-DOF mass-damper)";
  description_.model = "point_mass";
  description_.capabilities.measured_rates = true;
  description_.dof = 3;
  description_.joints = 3;
  description_.workspace_min = params.workspace_min;
  description_.workspace_max = params.workspace_max;
  description_.max_force = max_force;
  description_.apparent_mass = params.mass;
  description_.apparent_damping = params.damping;
  description_.simulated = true;
  if (rotation) {
    rotation_.emplace(rotation->params, rotation->initial);
    description_.name = "simulated point mass with a turning handle (6-DOF)";
    description_.dof = 6;
    description_.capabilities.orientation = true;
    description_.capabilities.torque = true;
    description_.max_torque = rotation->max_torque;
    description_.apparent_inertia = rotation->params.inertia;
    description_.apparent_rotational_damping = rotation->params.damping;
  }
}

DeviceStatus SimulatedPointMassDevice::read(DeviceReading& reading) {
  const engine::PointMassState& s = plant_.state();
  reading.q = {s.p_WT.x, s.p_WT.y, s.p_WT.z};
  reading.q_dot = {s.v_WT.x, s.v_WT.y, s.v_WT.z};
  if (sensor_ && engine::is_finite(s.p_WT)) {
    engine::Vec3 measured, velocity;
    sensor_->read(s.p_WT, last_period_s_, measured, velocity);
    reading.q = {measured.x, measured.y, measured.z};
    reading.q_dot = {velocity.x, velocity.y, velocity.z};
  }
  if (rotation_) {
    reading.R_WT = rotation_->state().R_WT;
    reading.w_WT = rotation_->state().w_WT;
  }
  return engine::is_finite(s.p_WT) && engine::is_finite(s.v_WT) ? DeviceStatus::kOk
                                                                : DeviceStatus::kError;
}

std::uint32_t SimulatedPointMassDevice::plant_joints(JointVector& q, JointVector& q_dot) const {
  const engine::PointMassState& s = plant_.state();
  q = {s.p_WT.x, s.p_WT.y, s.p_WT.z};
  q_dot = {s.v_WT.x, s.v_WT.y, s.v_WT.z};
  return 3;
}

DeviceStatus SimulatedPointMassDevice::write(const DeviceCommand& command, double dt) {
  last_period_s_ = dt;
  // A non-finite command is a fault: this tick runs with no device force.
  const engine::Vec3 F_command{command.tau[0], command.tau[1], command.tau[2]};
  const bool command_ok = engine::is_finite(F_command);
  const engine::Vec3 F_device = command_ok ? F_command : engine::Vec3{};
  double t = 0.0;
  const engine::HandInput& hand = hand_.begin_tick(t);
  plant_.set_added_mass(engine::hand_mass(hand));
  // The hand is sampled per sub-step, at the sub-step's start time.
  const double h = dt / static_cast<double>(plant_.params().substeps);
  plant_.step(F_device, dt, [&](const engine::Vec3& p_WT, const engine::Vec3& v_WT) {
    const engine::Vec3 F_hand = engine::hand_force(hand, p_WT, v_WT, t);
    t += h;
    return F_hand;
  });
  hand_.end_tick(dt);
  bool torque_ok = true;
  if (rotation_) {
    // Likewise a non-finite torque: none this tick.
    torque_ok = engine::is_finite(command.tau_W);
    const engine::Vec3 tau_device = torque_ok ? command.tau_W : engine::Vec3{};
    rotation_->step(tau_device, dt, [](const engine::Quat&, const engine::Vec3&) { return engine::Vec3{}; });
  }
  return command_ok && torque_ok && engine::is_finite(plant_.state().p_WT) ? DeviceStatus::kOk
                                                                           : DeviceStatus::kError;
}

}  // namespace haptic::runtime
