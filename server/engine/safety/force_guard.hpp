#pragma once
// The last stage before a force reaches a device: a non-finite force is a fault and becomes zero,
// the magnitude is saturated, the change per tick is rate-limited, and an output gain lets the
// server ramp everything to zero (shutdown). Runs on the loop: no allocation, no throw.

#include <cstdint>

#include "engine/core/vec3.hpp"

namespace haptic::engine {

/// The shortest time in which the guard lets a force go from zero to full scale (or back): the
/// rate limit is max_force / this. A glitch (a jump of the proxy, a client's bad update) then
/// reaches the hand as a 2 ms ramp, not as a step; a contact entered at K v below the limit (a
/// 1000 N/m wall at up to 10 m/s on a 20 N device: 20 N / 2 ms = 10,000 N/s) is untouched. Unit: s.
inline constexpr double kFullScaleForceRampTime = 0.002;

struct ForceLimits {
  double max_force = 20.0;        // Unit: N. Magnitude limit.
  double max_force_rate = 20.0 / kFullScaleForceRampTime;  // Unit: N/s. Largest change of any
                                                           // component; 0: unlimited.
};

/// A device's limits: its maximum force, reached from zero in kFullScaleForceRampTime at best.
inline ForceLimits force_limits_for(double max_force) {
  return ForceLimits{max_force, max_force / kFullScaleForceRampTime};
}

struct GuardedForce {
  Vec3 F_T_W;              // Unit: N.
  bool saturated = false;  // The magnitude or the rate limit cut the request.
  bool fault = false;      // The request was not finite and was replaced by zero.
};

class ForceGuard {
 public:
  explicit ForceGuard(const ForceLimits& limits) : limits_(limits) {}

  /// Filters one tick's requested force. dt is the tick period (s); output_gain in [0, 1] scales
  /// the request before the limits (1 normally, ramping to 0 on shutdown).
  GuardedForce apply(const Vec3& F_requested, double dt, double output_gain = 1.0);

  /// The last force let through.
  const Vec3& last() const { return last_; }
  void reset() { last_ = {}; }
  const ForceLimits& limits() const { return limits_; }

 private:
  ForceLimits limits_;
  Vec3 last_;
};

}  // namespace haptic::engine
