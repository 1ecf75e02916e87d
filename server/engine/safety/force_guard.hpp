#pragma once
// The last stage before a force reaches a device: a non-finite force is a fault and becomes zero,
// the magnitude is saturated, the change per tick is rate-limited, and an output gain lets the
// server ramp everything to zero (shutdown). Runs on the loop: no allocation, no throw.

#include <cstdint>

#include "engine/core/vec3.hpp"

namespace haptic::engine {

struct ForceLimits {
  double max_force = 20.0;         // Unit: N. Magnitude limit.
  double max_force_rate = 20000.0; // Unit: N/s. Largest change of any component; 0: unlimited.
};

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
