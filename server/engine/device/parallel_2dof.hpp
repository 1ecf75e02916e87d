#pragma once
// Document 001's device: a 2-DOF parallel (planar five-bar) haptic device with two grounded motors
// (Eom, Suh, Yi, "A Design Method of Haptic Interface Controller Considering Transparency and
// Robust Stability", §4: "a 2 DOF parallel type haptic device whose link length is 0.2 m", two
// AC servo motors with encoders, 1 ms sampling). Its Cartesian dynamics are eq. 2,
//   F = M_x(q) ẍ + V_x(q, q̇) + B_x(q) ẋ + H_x(q̇)   (G_x = 0: the device lies in a horizontal plane)
//   M_x = J^{-T} M J^{-1},  V_x = J^{-T}(V − M J^{-1} J̇ q̇),  B_x = J^{-T} B J^{-1},
//   H_x = J^{-T} H,
// coupled and pose-dependent, which is what the per-axis disturbance observer of
// engine/control/disturbance_observer.hpp removes (eqs. 3–5).
//
// Geometry (frame W, the device plane; z = 0 and out of the plane): motor i sits at A_i,
// A_1 = (−a/2, 0), A_2 = (+a/2, 0). Its proximal link (length l_1, angle q_i from +x) ends at the
// elbow B_i = A_i + l_1 (cos q_i, sin q_i); the two distal links (length l_2) meet at the end
// effector E = p_WT, the tool point. The working mode is elbows out: leg 1's elbow to the left of
// A_1→E, leg 2's to the right, E above the base (y > 0). The document gives only "link length
// 0.2 m"; here l_1 = l_2 = 0.2 m and the rest is chosen (see Parallel2DofParams).
//
// Mass model (an inference: the document gives no masses): each motor axis carries the rotor, its
// proximal link and half of its distal link lumped at the elbow, all as one constant inertia I
// about the axis; the end effector carries the handle and the other halves of the distal links as
// a point mass m_e. The kinetic energy is then ½ q̇ᵀ (I 𝟙) q̇ + ½ m_e |ẋ|², so in eq. 1
// M(q) = I 𝟙 and V(q, q̇) = 0 at the motor axes, and with G = J^{-1} (the inverse kinematics'
// Jacobian, ∂q/∂x):
//   M_x = I Gᵀ G + m_e 𝟙,   V_x = I Gᵀ h,  h = Ġ ẋ = q̈ − G ẍ,   B_x = b_j Gᵀ G,
// the joint viscous friction b_j and Coulomb friction f_c (eq. 1's B and H) acting at the motor
// axes. The document's identified per-axis values, m = 0.01 kg and b = 0.022 N·s/m in the wall's
// direction (§4), are of the same order as M_x and B_x along y at the workspace centre
// (0.016 kg, 0.023 N·s/m) — the nominal model the disturbance observer imposes.

#include <array>
#include <cmath>
#include <cstdint>
#include <string>

#include "engine/core/integrator.hpp"
#include "engine/core/vec3.hpp"
#include "engine/device/joint_friction.hpp"

namespace haptic::engine {

/// Geometry, masses and actuators of the five-bar. Defaults: the document's 0.2 m links; the rest
/// assumed (light carbon-tube links of about 10 g each and a 2 g handle give I and m_e; b_j and
/// f_c are of the order of a small direct-drive servo's bearing friction; the torque limit is
/// of the order of a 200 W AC servo's peak torque).
struct Parallel2DofParams {
  double base_separation = 0.1;     // a, distance between the motor axes A_1, A_2. Unit: m. >= 0.
  double proximal_length = 0.2;     // l_1 (document §4: 0.2 m). Unit: m. > 0.
  double distal_length = 0.2;       // l_2 (document §4: 0.2 m). Unit: m. > 0.
  double joint_inertia = 3.5e-4;    // I about each motor axis. Unit: kg·m². > 0.
  double end_effector_mass = 0.012; // m_e. Unit: kg. >= 0.
  double joint_viscous = 2e-3;      // b_j (eq. 1's B). Unit: N·m·s/rad. >= 0.
  double joint_coulomb = 0.0;       // f_c (eq. 1's H, smooth model). Unit: N·m. >= 0.
  double stick_velocity = 1e-3;     // v_s of the smooth Coulomb model. Unit: rad/s. > 0.
  double max_joint_torque = 2.0;    // Actuator limit per motor. Unit: N·m. > 0.
  IntegrationSettings integration{Integrator::kRk4, 10};  // substeps >= 1.

  /// Empty when every parameter is usable; otherwise one message naming the first bad parameter
  /// ("proximal_length: must be finite and > 0, got -0.2").
  std::string validate() const;
};

// Small planar types, in their own namespace so that other planar devices' helpers cannot collide.
namespace parallel_2dof {

/// A planar vector in W's x–y plane, or a pair of joint quantities. Units as named where used.
struct Planar {
  double x = 0.0;
  double y = 0.0;
};

/// A 2×2 matrix, row-major: [[a00, a01], [a10, a11]].
struct Matrix2 {
  double a00 = 0.0, a01 = 0.0, a10 = 0.0, a11 = 0.0;

  Planar operator*(const Planar& v) const { return {a00 * v.x + a01 * v.y, a10 * v.x + a11 * v.y}; }
  Matrix2 transposed() const { return {a00, a10, a01, a11}; }
  double determinant() const { return a00 * a11 - a01 * a10; }
  /// Solves this · u = v (the matrix must be invertible).
  Planar solve(const Planar& v) const {
    const double inv = 1.0 / determinant();
    return {(a11 * v.x - a01 * v.y) * inv, (a00 * v.y - a10 * v.x) * inv};
  }
};

}  // namespace parallel_2dof

/// Everything the dynamics need at one Cartesian state; NaN entries when the pose is out of reach.
struct Parallel2DofKinematics {
  parallel_2dof::Planar q;       // Motor angles (q_1, q_2). Unit: rad.
  parallel_2dof::Matrix2 G;      // ∂q/∂x = J^{-1}. Unit: rad/m.
  parallel_2dof::Planar q_dot;   // G ẋ. Unit: rad/s.
  parallel_2dof::Planar h;       // Ġ ẋ = q̈ − G ẍ. Unit: rad/s².
};

/// The five-bar's kinematics and eq. 2 dynamics, integrated in Cartesian coordinates
/// x = (x, y) = p_WT: state [x, y, ẋ, ẏ] stepped with integrate_tick<2> (core/integrator.hpp).
/// The motor torques are held over a tick (zero-order hold); the external force on the end
/// effector (the operator's hand) may depend on the state and is re-evaluated at every stage.
class Parallel2DofPlant {
 public:
  using Planar = parallel_2dof::Planar;
  using Matrix2 = parallel_2dof::Matrix2;
  using State = StateVector<4>;  // [x, y, ẋ, ẏ]. Units: m, m, m/s, m/s.

  /// `p_WT`, `v_WT`: initial end-effector position and velocity (z ignored); the position must be
  /// reachable in the working mode.
  Parallel2DofPlant(const Parallel2DofParams& params, const Vec3& p_WT, const Vec3& v_WT = {});

  // ---- Kinematics (pure functions of the parameters) ----

  /// q from x, each leg on its own: q_i = atan2(E − A_i) ± acos((l_1² + r_i² − l_2²)/(2 l_1 r_i)),
  /// r_i = |E − A_i| (+ for leg 1, − for leg 2: elbows out). False when out of reach.
  bool inverse_kinematics(const Planar& x, Planar& q) const;
  /// x from q: the intersection of the circles of radius l_2 about the elbows on the side the
  /// working mode puts it (left of B_1→B_2). False when the elbows are more than 2 l_2 apart.
  bool forward_kinematics(const Planar& q, Planar& x) const;
  /// J = ∂x/∂q at x (the inverse of G). Unit: m/rad.
  Matrix2 jacobian(const Planar& x) const;
  /// q, G = ∂q/∂x, q̇ = G ẋ and h = Ġ ẋ at (x, ẋ). From the leg constraint |E − B_i|² = l_2²,
  /// with e_i = E − B_i, u_i = (cos q_i, sin q_i), u_i⊥ = (−sin q_i, cos q_i):
  ///   q̇_i = e_i·ẋ / (l_1 e_i·u_i⊥),   h_i = (l_1 (e_i·u_i) q̇_i² + |ė_i|²) / (l_1 e_i·u_i⊥),
  ///   ė_i = ẋ − l_1 u_i⊥ q̇_i.
  Parallel2DofKinematics kinematics(const Planar& x, const Planar& x_dot) const;
  /// M_x = I GᵀG + m_e 𝟙 (eq. 2), with `added_mass` (kg) moving with the end effector. Unit: kg.
  Matrix2 cartesian_inertia(const Planar& x, double added_mass = 0.0) const;
  /// V_x = I Gᵀ h (eq. 2 with V = 0 at the motor axes). Unit: N.
  Planar cartesian_coriolis(const Planar& x, const Planar& x_dot) const;
  /// B_x = b_j GᵀG (eq. 2). Unit: N·s/m.
  Matrix2 cartesian_damping(const Planar& x) const;

  // ---- Dynamics ----

  /// ẍ = M_x^{-1} (Gᵀ (τ − b_j q̇ − H(q̇) − I h) + F_ext): eq. 2 solved for ẍ, with F = Gᵀ τ the
  /// motors' force at the end effector (τ = Jᵀ F). tau: Unit N·m; f_external: Unit N.
  Planar acceleration(const State& s, const Planar& tau, const Planar& f_external) const;

  /// One tick of length dt (s) under motor torques `tau` (N·m, saturated at max_joint_torque and
  /// held over the tick) and external(p_WT, v_WT) -> Vec3, the force on the end effector in W (N).
  template <typename ExternalForce>
  void step(const Planar& tau, double dt, ExternalForce&& external) {
    const Planar tau_sat{saturate(tau.x, params_.max_joint_torque),
                         saturate(tau.y, params_.max_joint_torque)};
    integrate_tick<2>(params_.integration, state_, dt, [&](const State& s) {
      const Vec3 f = external(Vec3{s[0], s[1], 0.0}, Vec3{s[2], s[3], 0.0});
      const Planar a = acceleration(s, tau_sat, {f.x, f.y});
      return State{s[2], s[3], a.x, a.y};
    });
  }
  /// One tick with no external force.
  void step(const Planar& tau, double dt);

  /// Motor torques that put the Cartesian force F (N) on the end effector, τ = Jᵀ(q) F (eq. 2's
  /// F = J^{-T} τ inverted), at the current pose. Unit: N·m.
  Planar joint_torque(const Planar& force) const;

  const State& state() const { return state_; }
  void set_state(const State& state) { state_ = state; }
  Vec3 p_WT() const { return {state_[0], state_[1], 0.0}; }
  Vec3 v_WT() const { return {state_[2], state_[3], 0.0}; }
  /// Motor angles at the current pose (NaN out of reach). Unit: rad.
  Planar joint_angles() const;

  /// Mass moving with the end effector besides m_e (a hand's grasp). Unit: kg, >= 0.
  void set_added_mass(double added_mass) { added_mass_ = added_mass; }
  double added_mass() const { return added_mass_; }

  const Parallel2DofParams& params() const { return params_; }

 private:
  Parallel2DofParams params_;
  CoulombViscousFriction friction_;
  State state_{};
  double added_mass_ = 0.0;
};

}  // namespace haptic::engine
