#include "runtime/parallel_dob_model.hpp"

#include <cmath>

#include "engine/device/joint_friction.hpp"

namespace haptic::runtime {
ParallelDobModel::ParallelDobModel(const engine::Parallel2DofParams& plant,
                                   const engine::DisturbanceObserverParams& observer,
                                   const engine::Vec3& reachable_p_WT, bool observer_enabled)
    : kinematics_(plant, reachable_p_WT),
      observers_{engine::DisturbanceObserver(observer), engine::DisturbanceObserver(observer)},
      observer_enabled_(observer_enabled),
      period_(observer.sample_period) {}

void ParallelDobModel::estimate(const DeviceReading& reading, double, bool, JointState& joints) {
  joints.q[0] = reading.q[0];
  joints.q[1] = reading.q[1];
  joints.q_dot[0] = reading.q_dot[0];
  joints.q_dot[1] = reading.q_dot[1];
}

void ParallelDobModel::kinematics(const JointState& joints, ToolReading& tool) {
  using engine::parallel_2dof::Planar;
  Planar x;
  if (!kinematics_.forward_kinematics({joints.q[0], joints.q[1]}, x)) {
    const double nan = std::nan("");
    tool.p_WT = tool.v_WT = v_WT_ = {nan, nan, nan};
    return;
  }
  G_ = kinematics_.kinematics(x, {}).G;
  const Planar x_dot = G_.solve({joints.q_dot[0], joints.q_dot[1]});  // q̇ = G ẋ
  tool.p_WT = {x.x, x.y, 0.0};
  tool.v_WT = v_WT_ = {x_dot.x, x_dot.y, 0.0};
}

DeviceStatus ParallelDobModel::joint_command(const ToolCommand& command, const DeviceReading& reading,
                                             const JointState&, double dt, DeviceCommand& out) {
  using engine::parallel_2dof::Planar;
  out = {};
  if (!engine::is_finite(command.F_T_W) || !(std::abs(dt - period_) <= 1e-9 * period_)) {
    return DeviceStatus::kError;
  }
  const engine::Vec3& v = v_WT_;
  Planar u{command.F_T_W.x, command.F_T_W.y};
  if (observer_enabled_) u = {observers_[0].command(u.x, v.x), observers_[1].command(u.y, v.y)};
  // τ = Jᵀ u (Gᵀ τ = u), saturated as the motors will; the force it puts on the end effector.
  const engine::parallel_2dof::Matrix2 Gt = G_.transposed();
  const Planar tau_wanted = Gt.solve(u);
  const double limit = kinematics_.params().max_joint_torque;
  const Planar tau{engine::saturate(tau_wanted.x, limit), engine::saturate(tau_wanted.y, limit)};
  if (observer_enabled_) {
    const Planar applied = Gt * tau;
    observers_[0].update(applied.x + reading.F_sensor_W.x, v.x);
    observers_[1].update(applied.y + reading.F_sensor_W.y, v.y);
  }
  out.tau[0] = tau.x;
  out.tau[1] = tau.y;
  return DeviceStatus::kOk;
}

engine::Vec3 ParallelDobModel::disturbance_estimate() const {
  if (!observer_enabled_) return {};
  return {observers_[0].last_estimate(), observers_[1].last_estimate(), 0.0};
}

}  // namespace haptic::runtime
