#pragma once
// Joint-level non-idealities shared by the documents' devices: Coulomb + viscous friction with a
// well-posed model near zero velocity, encoder quantization, and actuator saturation.
// Units: a rotary joint in rad, rad/s, N·m; a prismatic one in m, m/s, N (the formulas are the same).

#include <algorithm>
#include <cmath>

namespace haptic::engine {

/// Coulomb + viscous friction, τ_f = f_c sgn(q̇) + b q̇ (Madill 1998, §5.2, P(s) = 1/(Js² + Bs) with
/// u_f = f0 sgn(q̇); Russo 1990, eq. 3.38's F_d sgn(Ψ̇)). A pure sgn is ill-posed at q̇ = 0: a
/// fixed-step integrator chatters across zero and the ZOH turns that into a limit cycle (Madill,
/// L3211). Two well-posed versions:
///  - smooth(): f_c sat(q̇ / v_s) + b q̇, a steep linear region of width v_s around zero — what
///    Madill's estimator uses (f0 = 0.061 N·m, v0 = 0.03 rad/s);
///  - resisting(): Karnopp's stick model for simulation — inside |q̇| < v_s the friction cancels the
///    rest of the applied torque up to f_c, so a joint at rest stays at rest until the applied
///    torque exceeds f_c, with no creep.
struct CoulombViscousFriction {
  double coulomb = 0.0;  // f_c ≥ 0. Unit: N·m (or N).
  double viscous = 0.0;  // b ≥ 0. Unit: N·m·s/rad (or N·s/m).
  double stick_velocity = 1e-4;  // v_s > 0: the width of the region treated as zero velocity.

  /// The friction torque opposing motion (to subtract from the applied torque), smooth model.
  double smooth(double velocity) const {
    return coulomb * std::clamp(velocity / stick_velocity, -1.0, 1.0) + viscous * velocity;
  }

  /// The friction torque opposing motion, given `applied` (every other torque on the joint, the
  /// inertial one excluded). Outside the stick band: f_c sgn(q̇) + b q̇. Inside: as much of `applied`
  /// as f_c can hold, so q̈ = (applied − resisting) / J is zero while |applied| ≤ f_c.
  double resisting(double velocity, double applied) const {
    if (std::abs(velocity) >= stick_velocity) {
      return std::copysign(coulomb, velocity) + viscous * velocity;
    }
    return std::clamp(applied, -coulomb, coulomb) + viscous * velocity;
  }
};

/// An incremental encoder read as a position: counts = floor(q / resolution), reported as
/// counts · resolution (so the error is in [0, resolution)). resolution > 0. Madill's axial joint:
/// π/6000 rad/count (Table 5.2 as corrected in ch. 6, ≈ 157 µm at 0.30 m).
inline double quantize(double position, double resolution) {
  return std::floor(position / resolution) * resolution;
}

/// A symmetric actuator limit: what a command |u| > limit delivers. Madill's torque chain: DAC
/// ±5 V × transconductance × K_m → 7.23 N·m on the axial joint (Table 5.1).
inline double saturate(double command, double limit) {
  return std::clamp(command, -limit, limit);
}

}  // namespace haptic::engine
