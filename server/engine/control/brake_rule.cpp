#include "engine/control/brake_rule.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace haptic::engine {

std::string HybridRuleParams::validate() const {
  std::ostringstream out;
  if (!(std::isfinite(brake_limit) && brake_limit > 0.0)) {
    out << "brake_limit: must be finite and > 0, got " << brake_limit;
  } else if (!(std::isfinite(stick_velocity) && stick_velocity > 0.0)) {
    out << "stick_velocity: must be finite and > 0, got " << stick_velocity;
  }
  return out.str();
}

double brake_joint_torque(double brake, double q_dot) {
  if (q_dot == 0.0) return 0.0;
  return -std::copysign(brake, q_dot);
}

HybridSplit split_hybrid(double tau, double q_dot, double tau_user, const HybridRuleParams& params) {
  // Which way the brake would resist: against the motion, or near rest against the user's push.
  double resist_direction = 0.0;  // sign of the brake's joint torque when it is used
  if (std::abs(q_dot) >= params.stick_velocity) {
    if (tau * q_dot < 0.0) resist_direction = q_dot > 0.0 ? -1.0 : 1.0;  // eq. 4.6: P_in > 0
  } else if (tau * tau_user < 0.0) {
    resist_direction = tau_user > 0.0 ? -1.0 : 1.0;  // the wall case, L1041
  }
  if (resist_direction == 0.0) return {tau, 0.0};  // release: the motor (L1011)
  const double brake = std::min(std::abs(tau), params.brake_limit);
  return {tau - resist_direction * brake, brake};
}

HybridSplit EnergyBoundedRelease::limit(const HybridSplit& split, double q, double q_dot,
                                        double dt) {
  if (primed_) {
    const double dq = q - last_q_;
    stored_ += last_.brake * std::abs(dq) - last_.motor * dq;
  }
  primed_ = true;
  last_q_ = q;
  HybridSplit out = split;
  const double delivery = out.motor * q_dot * dt;  // > 0: the motor gives energy back
  if (delivery > 0.0) {
    // At most half of what is stored per tick: the prediction misses what the motion's
    // acceleration adds to Δq over the tick, and the margin covers it while |Δq| < 2 |q̇| dt.
    const double budget = 0.5 * std::max(stored_, 0.0);
    if (delivery > budget) out.motor *= budget / delivery;
  }
  last_ = out;
  return out;
}

}  // namespace haptic::engine
