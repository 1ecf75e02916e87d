#include "runtime/simulated_five_bar_device.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

namespace haptic::runtime {
namespace {

bool finite(const engine::FiveBarJoints& v) {
  return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}
bool finite(const engine::Vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace

SimulatedFiveBarDevice::SimulatedFiveBarDevice(const engine::FiveBarParams& params,
                                               const engine::FiveBarState& initial,
                                               const SimulatedFiveBarOptions& options)
    : options_(options), plant_(params, initial, options.plant) {
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
  difference_.cutoff = options.velocity_cutoff;
  set_plant_state(initial);
}

engine::FiveBarJoints SimulatedFiveBarDevice::measure(const engine::FiveBarJoints& q) const {
  return options_.quantized ? engine::five_bar_encoder_reading(plant_.params(), q) : q;
}

void SimulatedFiveBarDevice::set_plant_state(const engine::FiveBarState& state) {
  plant_.set_state(state);
  plant_.set_mode_state({});
  q_measured_ = measure(state.q);
  qdot_estimate_ = {};
  difference_.reset(q_measured_);
  if (estimator_) estimator_->reset(q_measured_);
}

void SimulatedFiveBarDevice::set_velocity_estimator(
    std::unique_ptr<FiveBarVelocityEstimator> estimator) {
  estimator_ = std::move(estimator);
  description_.capabilities.state_estimator = estimator_ != nullptr;
  if (estimator_) estimator_->reset(q_measured_);
}

DeviceStatus SimulatedFiveBarDevice::read(DeviceReading& reading) {
  const engine::FiveBarParams& p = plant_.params();
  // What the encoders give: the rigid tip of the measured joints, without link 5's deflection.
  reading.p_WT = engine::five_bar_tip_position(p, q_measured_);
  const engine::FiveBarMatrix J = engine::five_bar_jacobian(p, q_measured_);
  const engine::FiveBarJoints& w = qdot_estimate_;
  reading.v_WT = {J[0][0] * w[0] + J[0][1] * w[1] + J[0][2] * w[2],
                  J[1][0] * w[0] + J[1][1] * w[1] + J[1][2] * w[2],
                  J[2][0] * w[0] + J[2][1] * w[1] + J[2][2] * w[2]};
  const engine::FiveBarState& s = plant_.state();
  const engine::FiveBarModeState& mode = plant_.mode_state();
  return finite(reading.p_WT) && finite(reading.v_WT) && finite(s.q) && finite(s.qdot) &&
                 std::isfinite(mode.eta) && std::isfinite(mode.eta_dot)
             ? DeviceStatus::kOk
             : DeviceStatus::kError;
}

DeviceStatus SimulatedFiveBarDevice::write(const DeviceCommand& command, double dt) {
  const engine::FiveBarParams& p = plant_.params();
  // A non-finite command is a fault: the tick runs with zero motor torque.
  const bool command_ok = finite(command.F_T_W);
  const engine::FiveBarJoints tau =
      command_ok ? engine::five_bar_joint_torque(p, q_measured_, command.F_T_W)
                 : engine::FiveBarJoints{};
  double t = 0.0;
  const engine::HandInput& hand = hand_.begin_tick(t);
  const auto hand_on_tip = [&](const engine::Vec3& p_WT, const engine::Vec3& v_WT) {
    return engine::hand_force(hand, p_WT, v_WT, t);
  };
  plant_.step(tau, dt, hand_on_tip, engine::hand_mass(hand));
  hand_.end_tick(dt);

  const engine::FiveBarState& s = plant_.state();
  const engine::FiveBarModeState& mode = plant_.mode_state();
  if (!finite(s.q) || !finite(s.qdot) || !std::isfinite(mode.eta) || !std::isfinite(mode.eta_dot)) {
    return DeviceStatus::kError;
  }
  q_measured_ = measure(s.q);
  if (estimator_) {
    engine::Vec3 p_WT, v_WT;
    plant_.physical_tip_state(p_WT, v_WT);  // where the hand holds it
    const engine::FiveBarJoints tau_user =
        engine::five_bar_joint_torque(p, s.q, engine::hand_force(hand, p_WT, v_WT, t + dt));
    qdot_estimate_ = estimator_->update(q_measured_, plant_.applied_torque(), tau_user, dt);
  } else {
    qdot_estimate_ = difference_.update(q_measured_, dt);
  }
  return command_ok && finite(qdot_estimate_) ? DeviceStatus::kOk : DeviceStatus::kError;
}

}  // namespace haptic::runtime
