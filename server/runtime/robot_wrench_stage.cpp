#include "runtime/robot_wrench_stage.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/safety/passive_source.hpp"

namespace haptic::runtime {

RobotWrenchStage::RobotWrenchStage(const LatestValue<RobotWrench>& mailbox, const RobotWrenchParams& params,
                                   const DeviceDescription& description, bool torque, double period_s,
                                   std::int64_t ramp_ticks, std::atomic<std::uint64_t>& refused)
    : mailbox_(mailbox),
      params_(params),
      apparent_mass_(description.apparent_mass),
      apparent_inertia_(description.apparent_inertia),
      period_s_(period_s),
      ramp_ticks_(ramp_ticks),
      refused_(refused),
      layer_(engine::port_layer_params(description.apparent_mass, period_s)),
      // What is in the mailbox already (before a lockstep reset) is not rendered again: stale
      // until a new wrench comes.
      sequence_(mailbox.load().sequence),
      age_ticks_(std::numeric_limits<std::int64_t>::max()) {
  if (torque && description.apparent_inertia > 0.0) {
    torque_layer_.emplace(engine::port_layer_params(description.apparent_inertia, period_s));
  }
}

engine::Vec3 RobotWrenchStage::force(const ToolReading& reading) {
  const RobotWrench wrench = mailbox_.load();
  if (wrench.sequence != sequence_) {
    sequence_ = wrench.sequence;
    const engine::Vec3 F = params_.force_scale * wrench.F_T_W;
    const engine::Vec3 tau = params_.force_scale * wrench.tau_T_W;
    if (std::isfinite(F.x) && std::isfinite(F.y) && std::isfinite(F.z) && std::isfinite(tau.x) &&
        std::isfinite(tau.y) && std::isfinite(tau.z)) {
      F_T_W_ = F;
      tau_T_W_ = tau;
      age_ticks_ = 0;
    } else {
      // Refused: the last good force stays and ages as if nothing had come.
      refused_.fetch_add(1, std::memory_order_relaxed);
    }
  }
  if (sequence_ == 0) return {};  // nothing has come yet: no work to book
  // Fresh: the gain ramps (back) in; stale: out, over the loop's output ramp either way.
  const bool stale = static_cast<double>(age_ticks_) * period_s_ > params_.stale_s;
  const double step = 1.0 / static_cast<double>(ramp_ticks_);
  gain_ = stale ? std::max(0.0, gain_ - step) : std::min(1.0, gain_ + step);
  if (!stale) ++age_ticks_;
  // The robot's side books no energy: the reservoir holds exactly the work this port's user did
  // against the force less what the force gave back. The layer runs on after a ramp-out: a
  // deficit left by the last period is paid back, and the reservoir stays for the next wrench.
  // A device that does not know its mass is taken as the one the layer's default damper cap
  // stops in a period (0.05 kg at 1 kHz).
  const double mass = apparent_mass_ > 0.0 ? apparent_mass_ : engine::NetworkPassivityParams{}.max_damping * period_s_;
  return engine::from_passive_source(layer_, gain_ * F_T_W_, reading.v_WT, reading.p_WT, mass, period_s_);
}

engine::Vec3 RobotWrenchStage::torque(const ToolReading& reading) {
  // The handle's rotation since the last tick, in W (R_k = ΔR R_k−1), summed: the "position" whose
  // change the layer books the torque's work on.
  if (R_known_) theta_W_ += engine::rotation_vector(reading.R_WT * engine::conjugate(R_previous_));
  R_previous_ = reading.R_WT;
  R_known_ = true;
  if (sequence_ == 0) return {};
  return engine::from_passive_source(*torque_layer_, gain_ * tau_T_W_, reading.w_WT, theta_W_, apparent_inertia_,
                                     period_s_);
}

}  // namespace haptic::runtime
