#include "engine/control/joint_walls.hpp"
#include "engine/core/parameter_checks.hpp"

#include <cassert>
#include <cmath>
#include <sstream>

namespace haptic::engine {
std::string JointWallParams::validate() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  const auto non_negative = [](double v) { return std::isfinite(v) && v >= 0.0; };
  if (!non_negative(stiffness)) return bad_parameter("stiffness", "must be finite and >= 0", stiffness);
  if (!non_negative(damping)) return bad_parameter("damping", "must be finite and >= 0", damping);
  if (!positive(velocity_cutoff)) {
    return bad_parameter("velocity_cutoff", "must be finite and > 0", velocity_cutoff);
  }
  if (!positive(sample_period)) {
    return bad_parameter("sample_period", "must be finite and > 0", sample_period);
  }
  return {};
}

ConventionalJointWall::ConventionalJointWall(const JointWallParams& params)
    : params_(params),
      filter_weight_(1.0 - std::exp(-params.velocity_cutoff * params.sample_period)) {
  assert(params.validate().empty());
}

void ConventionalJointWall::reset(double q_previous) {
  q_previous_ = q_previous;
  velocity_ = 0.0;
}

double ConventionalJointWall::torque(double q_measured) {
  // First-order Euler difference (L3190), then the low-pass of eq. 6.2.
  const double raw = (q_measured - q_previous_) / params_.sample_period;
  q_previous_ = q_measured;
  velocity_ += filter_weight_ * (raw - velocity_);
  return -wall_gate(q_measured) * (params_.stiffness * q_measured + params_.damping * velocity_);
}

EstimatorJointWall::EstimatorJointWall(const JointWallParams& params,
                                       const StateEstimatorParams& estimator)
    : params_(params), estimator_(estimator) {
  assert(params.validate().empty());
  assert(params.sample_period == estimator.sample_period);
}

}  // namespace haptic::engine
