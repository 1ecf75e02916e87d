#include "runtime/simulated_five_bar_device.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace haptic::runtime {
namespace {

bool finite(const engine::FiveBarJoints& v) {
  return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}

}  // namespace

SimulatedFiveBarDevice::SimulatedFiveBarDevice(const engine::FiveBarParams& params,
                                               const engine::FiveBarState& initial,
                                               const SimulatedFiveBarOptions& options)
    : options_(options), plant_(params, initial, options.plant), noise_random_(options.noise_seed) {
  description_.joints = 3;
  description_.name = "simulated five-bar haptic device (003, Madill 1998, balanced, decoupled)";
  description_.model = "five_bar_003";
  description_.capabilities.gravity = false;  // counterbalanced (L2371–2380)
  description_.capabilities.friction = true;
  description_.capabilities.quantized_position = options.quantized;
  description_.capabilities.flexible_modes = options.plant.flexible_mode;
  description_.dof = 3;
  description_.max_force = options.max_force;
  description_.simulated = true;
  // Workspace box: the tip over a joint box around home, q0 ∈ ±45°, q1 ∈ [45°, 135°],
  // q2 ∈ [135°, 225°] [inference: the thesis gives no joint ranges; Table 5.6's poses lie inside].
  const double deg = std::numbers::pi / 180.0;
  engine::Vec3 lo{1e9, 1e9, 1e9}, hi{-1e9, -1e9, -1e9};
  for (int a = 0; a <= 10; ++a) {
    for (int b = 0; b <= 10; ++b) {
      for (int c = 0; c <= 10; ++c) {
        const engine::Vec3 p = engine::five_bar_tip_position(
            params, {(-45.0 + 9.0 * a) * deg, (45.0 + 9.0 * b) * deg, (135.0 + 9.0 * c) * deg});
        lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
        hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
      }
    }
  }
  description_.workspace_min = lo;
  description_.workspace_max = hi;
  description_.capabilities.state_estimator = options.state_estimator;
  set_plant_state(initial);
}

engine::FiveBarJoints SimulatedFiveBarDevice::measure(const engine::FiveBarJoints& q) {
  engine::FiveBarJoints sensed = q;
  for (std::size_t i = 0; i < 3; ++i) {
    if (options_.encoder_noise[i] > 0.0) sensed[i] += options_.encoder_noise[i] * unit_noise_(noise_random_);
  }
  return options_.quantized ? engine::five_bar_encoder_reading(plant_.params(), sensed) : sensed;
}

void SimulatedFiveBarDevice::set_plant_state(const engine::FiveBarState& state) {
  plant_.set_state(state);
  plant_.set_mode_state({});
  q_measured_ = measure(state.q);
}

bool SimulatedFiveBarDevice::state_finite() const {
  const engine::FiveBarState& s = plant_.state();
  const engine::FiveBarModeState& mode = plant_.mode_state();
  return finite(s.q) && finite(s.qdot) && std::isfinite(mode.eta) && std::isfinite(mode.eta_dot);
}

std::uint32_t SimulatedFiveBarDevice::plant_joints(JointVector& q, JointVector& q_dot) const {
  const engine::FiveBarState& s = plant_.state();
  q = {s.q[0], s.q[1], s.q[2]};
  q_dot = {s.qdot[0], s.qdot[1], s.qdot[2]};
  return 3;
}

std::optional<JointSpaceDynamics> SimulatedFiveBarDevice::joint_space_dynamics() const {
  const engine::FiveBarJoints& q = plant_.state().q;
  JointSpaceDynamics out;
  out.inertia = plant_.mass_matrix(q);
  for (std::size_t i = 0; i < 3; ++i) out.damping[i][i] = plant_.params().friction[i].viscous;
  out.jacobian = engine::five_bar_jacobian(plant_.params(), q);
  return out;
}

DeviceStatus SimulatedFiveBarDevice::read(DeviceReading& reading) {
  if (!state_finite()) return DeviceStatus::kError;
  reading.q = {q_measured_[0], q_measured_[1], q_measured_[2]};
  // The strain gauges: the operator's force where the hand holds the tip, through Jᵀ(q).
  double t = 0.0;
  const engine::HandInput& hand = hand_.begin_tick(t);
  engine::Vec3 p_WT, v_WT;
  plant_.physical_tip_state(p_WT, v_WT);
  const engine::FiveBarJoints tau_user =
      engine::five_bar_joint_torque(plant_.params(), plant_.state().q, engine::hand_force(hand, p_WT, v_WT, t));
  reading.tau_sensor = {tau_user[0], tau_user[1], tau_user[2]};
  return DeviceStatus::kOk;
}

DeviceStatus SimulatedFiveBarDevice::write(const DeviceCommand& command, double dt) {
  // A non-finite command is a fault: the tick runs with zero motor torque.
  const engine::FiveBarJoints tau_command{command.tau[0], command.tau[1], command.tau[2]};
  const bool command_ok = finite(tau_command);
  const engine::FiveBarJoints tau = command_ok ? tau_command : engine::FiveBarJoints{};
  double t = 0.0;
  const engine::HandInput& hand = hand_.begin_tick(t);
  const auto hand_on_tip = [&](const engine::Vec3& p_WT, const engine::Vec3& v_WT) {
    return engine::hand_force(hand, p_WT, v_WT, t);
  };
  plant_.step(tau, dt, hand_on_tip, engine::hand_mass(hand));
  hand_.end_tick(dt);
  if (!state_finite()) return DeviceStatus::kError;
  q_measured_ = measure(plant_.state().q);
  return command_ok ? DeviceStatus::kOk : DeviceStatus::kError;
}

}  // namespace haptic::runtime
