#include "engine/safety/force_guard.hpp"

#include <algorithm>

namespace haptic::engine {
namespace {

double limit_step(double target, double last, double max_step, bool& cut) {
  const double step = target - last;
  if (step > max_step) {
    cut = true;
    return last + max_step;
  }
  if (step < -max_step) {
    cut = true;
    return last - max_step;
  }
  return target;
}

}  // namespace

GuardedForce ForceGuard::apply(const Vec3& F_requested, double dt, double output_gain) {
  GuardedForce out;
  const Vec3 F = std::clamp(output_gain, 0.0, 1.0) * F_requested;
  if (!is_finite(F)) {
    // A NaN or inf is a fault, never an output: command zero and restart the rate limiter there.
    out.fault = true;
    last_ = {};
    out.F_T_W = last_;
    return out;
  }
  Vec3 limited = F;
  if (limits_.max_force_rate > 0.0) {
    const double max_step = limits_.max_force_rate * dt;
    limited.x = limit_step(F.x, last_.x, max_step, out.saturated);
    limited.y = limit_step(F.y, last_.y, max_step, out.saturated);
    limited.z = limit_step(F.z, last_.z, max_step, out.saturated);
  }
  const double magnitude = norm(limited);
  if (magnitude > limits_.max_force) {
    limited *= limits_.max_force / magnitude;
    out.saturated = true;
  }
  last_ = limited;
  out.F_T_W = limited;
  return out;
}

}  // namespace haptic::engine
