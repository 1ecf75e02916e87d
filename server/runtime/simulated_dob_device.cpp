#include "runtime/simulated_dob_device.hpp"

#include <cmath>

#include "engine/device/joint_friction.hpp"

namespace haptic::runtime {
namespace {

bool finite_state(const engine::Parallel2DofPlant::State& s) {
  return std::isfinite(s[0]) && std::isfinite(s[1]) && std::isfinite(s[2]) && std::isfinite(s[3]);
}

}  // namespace

SimulatedDobDevice::SimulatedDobDevice(const engine::Parallel2DofParams& plant,
                                       const engine::DisturbanceObserverParams& observer,
                                       const engine::Vec3& initial_p_WT, double max_force,
                                       bool observer_enabled)
    : plant_(plant, initial_p_WT),
      observers_{engine::DisturbanceObserver(observer), engine::DisturbanceObserver(observer)},
      observer_enabled_(observer_enabled),
      period_(observer.sample_period) {
  description_.name = observer_enabled
                          ? "simulated 2-DOF parallel device with disturbance observer (001)"
                          : "simulated 2-DOF parallel device without disturbance observer (001)";
  description_.model = "parallel_2dof_001";
  description_.capabilities.gravity = false;  // horizontal plane
  description_.capabilities.friction = plant.joint_coulomb > 0.0 || plant.joint_viscous > 0.0;
  description_.capabilities.force_sensor = observer_enabled;  // the handle's, used by the observer
  description_.capabilities.disturbance_observer = observer_enabled;
  description_.dof = 2;
  // A box inside the elbows-out workspace of the default geometry (l_1 = l_2 = 0.2 m, a = 0.1 m),
  // clear of the boundary singularities.
  description_.workspace_min = {-0.1, 0.15, 0.0};
  description_.workspace_max = {0.1, 0.32, 0.0};
  description_.max_force = max_force;
  if (observer_enabled) {  // below Q's cut-off each axis is the nominal mass-damper (eq. 5)
    description_.apparent_mass = observer.nominal_mass;
    description_.apparent_damping = observer.nominal_damping;
  }
  description_.simulated = true;
}

DeviceStatus SimulatedDobDevice::read(DeviceReading& reading) {
  reading.p_WT = plant_.p_WT();
  reading.v_WT = plant_.v_WT();
  return finite_state(plant_.state()) ? DeviceStatus::kOk : DeviceStatus::kError;
}

DeviceStatus SimulatedDobDevice::write(const DeviceCommand& command, double dt) {
  using engine::parallel_2dof::Planar;
  if (!engine::is_finite(command.F_T_W) || !(std::abs(dt - period_) <= 1e-9 * period_) ||
      !finite_state(plant_.state())) {
    return DeviceStatus::kError;
  }
  double t = 0.0;
  const engine::HandInput& hand = hand_.begin_tick(t);
  plant_.set_added_mass(engine::hand_mass(hand));
  const engine::Vec3 p = plant_.p_WT();
  const engine::Vec3 v = plant_.v_WT();
  hand_force_ = engine::hand_force(hand, p, v, t);
  hand_force_.z = 0.0;

  Planar u{command.F_T_W.x, command.F_T_W.y};
  if (observer_enabled_) {
    u = {observers_[0].command(u.x, v.x), observers_[1].command(u.y, v.y)};
  }
  // τ = Jᵀ u (Gᵀ τ = u), saturated as the plant will; the force it puts on the end effector.
  const engine::parallel_2dof::Matrix2 Gt = plant_.kinematics({p.x, p.y}, {}).G.transposed();
  const Planar tau_wanted = Gt.solve(u);
  const double limit = plant_.params().max_joint_torque;
  const Planar tau{engine::saturate(tau_wanted.x, limit), engine::saturate(tau_wanted.y, limit)};
  const Planar applied = Gt * tau;

  plant_.step(tau, dt, [&](const engine::Vec3& p_WT, const engine::Vec3& v_WT) {
    return engine::hand_force(hand, p_WT, v_WT, t);
  });
  if (observer_enabled_) {
    observers_[0].update(applied.x + hand_force_.x, v.x);
    observers_[1].update(applied.y + hand_force_.y, v.y);
  }
  hand_.end_tick(dt);
  return finite_state(plant_.state()) ? DeviceStatus::kOk : DeviceStatus::kError;
}

engine::Vec3 SimulatedDobDevice::disturbance_estimate() const {
  if (!observer_enabled_) return {};
  return {observers_[0].last_estimate(), observers_[1].last_estimate(), 0.0};
}

}  // namespace haptic::runtime
