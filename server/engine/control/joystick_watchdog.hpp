#pragma once
// Document 004's software watchdog (Russo 1990, L510; code `safety()`, L1920–L1958): the drive
// shaft velocities are checked every loop; if |θ̇| or |Φ̇| exceeds 8 rad/s or |Ṙ| exceeds
// 0.7143 m/s, every motor goes to zero and every brake to its maximum (DAC 0 is the brakes' full
// torque: counts = 3900 − τ k), and the program waits for the user's button before it releases
// the brakes. Here: trip, latch, and stay latched until rearm().
//
// A non-finite velocity trips it too (the comparison is written so that NaN fails it). The
// original compares with C's integer abs(), which truncates a double: as compiled it tripped only
// from 9 rad/s and from 1 m/s — the intended thresholds are used here.

#include <cmath>

namespace haptic::engine {

struct JoystickWatchdogLimits {
  double gimbal_rate = 8.0;     // |θ̇|, |Φ̇| limit (L1930). Unit: rad/s.
  double shaft_speed = 0.7143;  // |Ṙ| limit (L1930). Unit: m/s.
};

class JoystickWatchdog {
 public:
  explicit JoystickWatchdog(const JoystickWatchdogLimits& limits = {}) : limits_(limits) {}

  /// Once per loop with the measured rates (rad/s, rad/s, m/s). Returns true while tripped.
  bool check(double theta_dot, double phi_dot, double R_dot) {
    const bool within = std::abs(theta_dot) <= limits_.gimbal_rate &&
                        std::abs(phi_dot) <= limits_.gimbal_rate &&
                        std::abs(R_dot) <= limits_.shaft_speed;
    if (!within) tripped_ = true;
    return tripped_;
  }
  /// Latches: only rearm() clears it (the original waits for the mouse button, L1951).
  bool tripped() const { return tripped_; }
  void trip() { tripped_ = true; }
  void rearm() { tripped_ = false; }
  const JoystickWatchdogLimits& limits() const { return limits_; }

 private:
  JoystickWatchdogLimits limits_;
  bool tripped_ = false;
};

}  // namespace haptic::engine
