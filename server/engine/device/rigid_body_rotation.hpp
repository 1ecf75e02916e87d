#pragma once
// The handle's rotation for the 6-DOF simulated device: a rigid body with isotropic inertia I and
// viscous rotational damping b about its centre, I ω̇ = τ − b ω (ω, τ in W). With I·𝟙 the
// gyroscopic term ω × (I ω) is zero, so Euler's equations are linear, one mass-damper per axis,
// and the angular velocity is stepped exactly (ExactMassDamperStep). The orientation follows
// Ṙ_WT = [ω]× R_WT: each sub-step rotates by exp(Δθ), Δθ = ∫ω dt over the sub-step (exact per
// axis). That is exact whenever ω keeps its direction (a rotation about one axis: the stability
// analysis's case) and second order in the sub-step otherwise (the commutator of successive Δθ).

#include <cstdint>
#include <string>

#include "engine/core/rotation.hpp"
#include "engine/core/vec3.hpp"
#include "engine/device/exact_step.hpp"

namespace haptic::engine {

struct RotationParams {
  double inertia = 2e-5;   // I about every axis through the centre. Unit: kg·m². > 0.
  double damping = 1e-4;   // b. Unit: N·m·s/rad. ≥ 0.
  std::uint32_t substeps = 10;  // Sub-steps per tick, ≥ 1.
};

/// "" or one message naming the bad parameter ("inertia: must be finite and > 0, got 0").
std::string validate_rotation(const RotationParams& params);

struct RotationState {
  Quat R_WT;   // The tool's orientation. Unit quaternion.
  Vec3 w_WT;   // Its angular velocity in W. Unit: rad/s.
};

class RigidBodyRotation {
 public:
  explicit RigidBodyRotation(const RotationParams& params, const RotationState& initial = {})
      : params_(params), state_(initial) {}

  /// One tick of dt under the device's torque tau_device (N·m, held over the tick) plus an
  /// external torque external_torque(R_WT, w_WT) (the hand's), re-evaluated every sub-step.
  template <typename ExternalTorque>
  void step(const Vec3& tau_device, double dt, ExternalTorque&& external_torque) {
    const double h = dt / static_cast<double>(params_.substeps);
    if (h != step_.h) step_ = ExactMassDamperStep::of(params_.inertia, params_.damping, h);
    for (std::uint32_t i = 0; i < params_.substeps; ++i) {
      advance(tau_device + external_torque(state_.R_WT, state_.w_WT));
    }
  }

  const RotationState& state() const { return state_; }
  void set_state(const RotationState& state) { state_ = state; }
  const RotationParams& params() const { return params_; }

 private:
  void advance(const Vec3& tau) {
    const double inv = 1.0 / params_.inertia;
    Vec3 delta;  // ∫ω dt over the sub-step. Unit: rad.
    delta.x = step_.displacement(state_.w_WT.x, tau.x * inv);
    delta.y = step_.displacement(state_.w_WT.y, tau.y * inv);
    delta.z = step_.displacement(state_.w_WT.z, tau.z * inv);
    double unused = 0.0;
    step_.advance(unused, state_.w_WT.x, tau.x * inv);
    step_.advance(unused, state_.w_WT.y, tau.y * inv);
    step_.advance(unused, state_.w_WT.z, tau.z * inv);
    // Renormalised each sub-step so round-off never drifts |q| from 1.
    state_.R_WT = normalized(rotation_from_vector(delta) * state_.R_WT);
  }

  RotationParams params_;
  RotationState state_;
  ExactMassDamperStep step_;
};

}  // namespace haptic::engine
