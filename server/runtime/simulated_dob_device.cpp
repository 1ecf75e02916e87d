#include "runtime/simulated_dob_device.hpp"

#include <cmath>

namespace haptic::runtime {
namespace {

bool finite_state(const engine::Parallel2DofPlant::State& s) {
  return std::isfinite(s[0]) && std::isfinite(s[1]) && std::isfinite(s[2]) && std::isfinite(s[3]);
}

}  // namespace

SimulatedDobDevice::SimulatedDobDevice(const engine::Parallel2DofParams& plant,
                                       const engine::Vec3& initial_p_WT, double max_force,
                                       bool observer_enabled, double nominal_mass,
                                       double nominal_damping)
    : plant_(plant, initial_p_WT) {
  description_.name = observer_enabled
                          ? "simulated 2-DOF parallel device with disturbance observer (001)"
                          : "simulated 2-DOF parallel device without disturbance observer (001)";
  description_.model = "parallel_2dof_001";
  description_.capabilities.gravity = false;  // horizontal plane
  description_.capabilities.friction = plant.joint_coulomb > 0.0 || plant.joint_viscous > 0.0;
  description_.capabilities.force_sensor = observer_enabled;  // the handle's, used by the observer
  description_.capabilities.disturbance_observer = observer_enabled;
  description_.capabilities.measured_rates = true;
  description_.dof = 2;
  description_.joints = 2;
  // A box inside the elbows-out workspace of the default geometry (l_1 = l_2 = 0.2 m, a = 0.1 m),
  // clear of the boundary singularities.
  description_.workspace_min = {-0.1, 0.15, 0.0};
  description_.workspace_max = {0.1, 0.32, 0.0};
  description_.max_force = max_force;
  if (observer_enabled) {  // below Q's cut-off each axis is the nominal mass-damper (eq. 5)
    description_.apparent_mass = nominal_mass;
    description_.apparent_damping = nominal_damping;
  }
  description_.simulated = true;
}

std::uint32_t SimulatedDobDevice::plant_joints(JointVector& q, JointVector& q_dot) const {
  const auto& s = plant_.state();
  const engine::Parallel2DofKinematics k = plant_.kinematics({s[0], s[1]}, {s[2], s[3]});
  q[0] = k.q.x;
  q[1] = k.q.y;
  q_dot[0] = k.q_dot.x;
  q_dot[1] = k.q_dot.y;
  return 2;
}

DeviceStatus SimulatedDobDevice::read(DeviceReading& reading) {
  if (!finite_state(plant_.state())) return DeviceStatus::kError;
  plant_joints(reading.q, reading.q_dot);
  // The handle's sensor at the start of the tick.
  double t = 0.0;
  const engine::HandInput& hand = hand_.begin_tick(t);
  hand_force_ = engine::hand_force(hand, plant_.p_WT(), plant_.v_WT(), t);
  hand_force_.z = 0.0;
  reading.F_sensor_W = hand_force_;
  return std::isfinite(reading.q[0]) && std::isfinite(reading.q[1]) && engine::is_finite(hand_force_)
             ? DeviceStatus::kOk
             : DeviceStatus::kError;
}

DeviceStatus SimulatedDobDevice::write(const DeviceCommand& command, double dt) {
  using engine::parallel_2dof::Planar;
  if (!std::isfinite(command.tau[0]) || !std::isfinite(command.tau[1]) ||
      !finite_state(plant_.state())) {
    return DeviceStatus::kError;
  }
  double t = 0.0;
  const engine::HandInput& hand = hand_.begin_tick(t);
  plant_.set_added_mass(engine::hand_mass(hand));
  plant_.step(Planar{command.tau[0], command.tau[1]}, dt,
              [&](const engine::Vec3& p_WT, const engine::Vec3& v_WT) {
                return engine::hand_force(hand, p_WT, v_WT, t);
              });
  hand_.end_tick(dt);
  return finite_state(plant_.state()) ? DeviceStatus::kOk : DeviceStatus::kError;
}

}  // namespace haptic::runtime
