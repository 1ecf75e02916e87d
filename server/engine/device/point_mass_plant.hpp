#pragma once
// The default simulated device: a 3-DOF Cartesian mass-damper, m x'' + b x' = F on each axis
// (Eom, Suh, Yi, eq. 5: the per-axis plant a disturbance observer leaves, P(s) = 1/(ms + b);
// m = 0.01 kg, b = 0.022 N*s/m in their experiment).

#include <cstdint>
#include <functional>

#include "engine/core/vec3.hpp"
#include "engine/device/exact_step.hpp"

namespace haptic::engine {

struct PointMassParams {
  double mass = 0.01;        // Unit: kg. > 0.
  double damping = 0.022;    // Unit: N*s/m. >= 0.
  std::uint32_t substeps = 10;  // Sub-steps per tick, >= 1.
  /// Coulomb friction on each axis of W, with stick: an axis at rest stays so while the force on
  /// it is within c, and one whose velocity would cross zero within a sub-step stops there (the
  /// model an identification fits where friction holds a device still). Unit: N. >= 0; 0: none.
  double coulomb = 0.0;
  /// τ_a: the device force reaches the mass through 1/(1 + s τ_a) (an actuator's lag). Unit: s.
  /// >= 0; 0: none.
  double actuator_lag = 0.0;
  Vec3 workspace_min{-0.1, -0.1, -0.1};  // Unit: m. The plant stops at the box (inelastic).
  Vec3 workspace_max{0.1, 0.1, 0.1};
};

struct PointMassState {
  Vec3 p_WT;  // Tool position. Unit: m.
  Vec3 v_WT;  // Tool velocity. Unit: m/s.
};

/// Integrates the plant over one tick of length dt under the device force F_device (held constant
/// over the tick, as a zero-order hold does) plus an external force that may depend on the state
/// (the operator's hand), re-evaluated at every sub-step.
///
/// Each sub-step of length h = dt / substeps holds the total force F constant and advances the
/// mass-damper exactly: v' = v e^{-h b/m} + (F/b)(1 - e^{-h b/m}), and x' from the integral of v
/// (with b = 0 handled as the limit). The scheme is therefore exact for a constant force and
/// unconditionally stable in the plant's own dynamics; its only error comes from the operator
/// force being sampled per sub-step. With a lag, the device force over a sub-step is the lag's
/// exact mean over it; with friction, a stop within a sub-step is exact (its time solved).
class PointMassPlant {
 public:
  explicit PointMassPlant(const PointMassParams& params, const PointMassState& initial = {});

  /// external_force(p_WT, v_WT) -> force on the tool from outside the device (N).
  /// Not allocating: takes a plain function reference.
  template <typename ExternalForce>
  void step(const Vec3& F_device, double dt, ExternalForce&& external_force) {
    const double h = dt / static_cast<double>(params_.substeps);
    if (h != coefficients_.h) {  // once, while dt is constant
      coefficients_ = ExactMassDamperStep::of(params_.mass + added_mass_, params_.damping, h);
    }
    for (std::uint32_t i = 0; i < params_.substeps; ++i) {
      const Vec3 F_total = through_lag(F_device, h) + external_force(state_.p_WT, state_.v_WT);
      advance_exact(F_total);
    }
  }

  /// Mass moving with the tool besides the device's own (a hand's grasp). Unit: kg, >= 0.
  void set_added_mass(double added_mass) {
    if (added_mass == added_mass_) return;
    added_mass_ = added_mass;
    coefficients_.h = -1.0;  // the step weights depend on the mass
  }
  double added_mass() const { return added_mass_; }

  const PointMassState& state() const { return state_; }
  void set_state(const PointMassState& state) { state_ = state; }
  const PointMassParams& params() const { return params_; }

 private:
  void advance_exact(const Vec3& F);
  /// One axis over a sub-step under F (N), with Coulomb friction and stick.
  void advance_with_friction(double& x, double& v, double F, double m) const;
  /// The device force's mean over the next sub-step h through the lag (F itself without one),
  /// and the lag's state advanced to the sub-step's end.
  Vec3 through_lag(const Vec3& F_device, double h);

  PointMassParams params_;
  Vec3 lagged_force_{};  // the lag's output at the sub-step's start. Unit: N.
  PointMassState state_;
  ExactMassDamperStep coefficients_;  // for the sub-step h while dt is constant
  double added_mass_ = 0.0;
};

}  // namespace haptic::engine
