#pragma once
// Orientation fields: torques on the tool's orientation R_WT, the rotational counterparts of the
// spring and detent fields (docs/scene.md, "Orientation fields").
//
// Frames and units per docs/architecture.md: R_WT the tool's orientation, ω_WT its angular
// velocity in W (rad/s), τ_T_W the torque on the tool in W (N·m). The error of an orientation
// R_WT against a target R_WG is the rotation vector θ = log(R_WT R_WG⁻¹) in W (rad, |θ| ≤ π;
// engine/core/rotation.hpp).
//
// The spring's law is a contact's impedance law applied per component of θ: each component is a
// "penetration" d_i = −θ_i and the torque τ_i = f_i, so the same four choices (the measured
// velocity, backward difference, exact ZOH, Tustin; 000 eqs. 8.9–8.16) and the same stability
// analysis hold — about one axis the rotation is exactly a 1-DOF mass-damper, I θ̈ + b θ̇ = τ, with
// the handle's inertia in place of the mass.
//
// validate_*() run off the loop and return "" or one message naming the bad parameter;
// OrientationSpringState::update and evaluate_orientation_detent run per tick, allocate nothing and
// never throw.

#include <array>
#include <cstdint>
#include <string>

#include "engine/core/rotation.hpp"
#include "engine/core/vec3.hpp"
#include "engine/scene/impedance.hpp"

namespace haptic::engine {

/// τ = −k θ − b ω (clipped to max_torque when > 0); U = ½ k |θ|².
struct OrientationSpringSpec {
  Quat R_WG;                  // The target orientation. Unit quaternion.
  double stiffness = 0.0;     // k. Unit: N·m/rad. ≥ 0.
  double damping = 0.0;       // b. Unit: N·m·s/rad. ≥ 0.
  double max_torque = 0.0;    // Unit: N·m. ≥ 0; 0: no clip.
  /// kVelocity: τ = −k θ − b ω with the measured ω; a discrete law: the ImpedanceFilter on −θ_i.
  ContactLaw law = ContactLaw::kVelocity;
};

/// The translational detent's profile (DetentFieldSpec) over the angle ρ = |θ| to the target:
///   U = −D + (D + H) s(ρ/R) for ρ ≤ R, H (1 − s((ρ − R)/w)) for R < ρ < R + w, 0 beyond,
/// s(t) = 3t² − 2t³; τ = −U′(ρ) θ/ρ − b ω while ρ < R + w. Near the target a rotational spring of
/// stiffness 6 (D + H)/R² (N·m/rad).
struct OrientationDetentSpec {
  Quat R_WG;                 // The target orientation. Unit quaternion.
  double depth = 0.0;        // D. Unit: J. > 0.
  double radius = 0.0;       // R. Unit: rad. > 0.
  double rim_height = 0.0;   // H. Unit: J. ≥ 0.
  double rim_width = 0.0;    // w. Unit: rad. > 0 when H > 0; R + w ≤ π.
  double damping = 0.0;      // b. Unit: N·m·s/rad. ≥ 0.
};

/// "" or one message naming the bad parameter and its value ("stiffness: must be finite and >= 0,
/// got -1"). T: the loop period the discrete laws are built for. Unit: s.
std::string validate_orientation_spring(const OrientationSpringSpec& spec, double T);
std::string validate_orientation_detent(const OrientationDetentSpec& spec);

/// What an orientation field gives at one tick.
struct OrientationSample {
  Vec3 tau_T_W;                // Torque on the tool, in W. Unit: N·m.
  double U = 0.0;              // Potential energy stored in the field. Unit: J.
  bool has_potential = false;  // the torque's conservative part is −∇U here.
};

/// The discrete law's weights for a spring (impedance_weights of (k, b) with no inertia term);
/// zero weights for kVelocity. Off the loop.
ImpedanceWeights orientation_spring_weights(const OrientationSpringSpec& spec, double T);

/// One spring's per-port state: a filter per component of θ, started at the first update.
struct OrientationSpringState {
  std::array<ImpedanceFilter, 3> filters;
  Vec3 theta_previous;  // θ at the previous update. Unit: rad.
  bool started = false;

  /// Builds the filters for weights (kept: a new version of the spring carries its history over).
  void set_weights(const ImpedanceWeights& weights) {
    for (ImpedanceFilter& filter : filters) filter = ImpedanceFilter(weights);
    started = false;
  }
  void copy_history_from(const OrientationSpringState& other) {
    for (std::size_t i = 0; i < 3; ++i) filters[i].copy_history_from(other.filters[i]);
    theta_previous = other.theta_previous;
    started = other.started;
  }

  /// The spring's torque for the tool at R_WT turning at ω_WT (rad/s), T the period (s). The
  /// discrete laws start (and restart, when θ jumps by more than π: the error crossed the far
  /// side, where its branch flips) from θ(k−1) = θ(k) − T ω so the first difference is the
  /// measured rate, never a spike.
  OrientationSample update(const OrientationSpringSpec& spec, const Quat& R_WT, const Vec3& w_WT,
                           double T);
};

/// The detent's torque and potential for the tool at R_WT turning at ω_WT (rad/s). Stateless.
OrientationSample evaluate_orientation_detent(const OrientationDetentSpec& spec, const Quat& R_WT,
                                              const Vec3& w_WT);

}  // namespace haptic::engine
