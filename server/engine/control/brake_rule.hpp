#pragma once
// The hybrid motor/brake power rule of document 004 (Russo 1990, §4.3, L957–L1060) and the
// element laws it is stated for, per joint axis.
//
// Sign convention (one for the whole file): τ is the torque an actuator or a simulated element
// applies to the joint; q̇ the joint velocity. Power flows INTO the element (work is done on it by
// the user) when τ q̇ < 0 — the document's P_in = τ_b θ̇ > 0 (eq. 4.6), whose τ_b is the torque the
// shaft applies to the brake, −τ here. A brake is a Coulomb element (L963): it applies
// −b sgn(q̇) with a clamping torque b ≥ 0, so it can only take power in.
//
// The rule (L1011): "activate the brakes whenever a dissipative or energy storage element is
// simulated with a positive power, that is work is done on the element. The release of energy,
// or negative power flow, then is accomplished by the motor torque commands". Per axis:
//   |q̇| ≥ v_s:  τ q̇ < 0  → brake b = min(|τ|, b_max), motor the rest of τ (zero unless b_max
//                           is reached); otherwise brake 0, motor τ.
//   |q̇| < v_s:  the velocity says nothing; decide on the user's torque τ_u (the measured force
//               mapped to the joint): pushing against the element, τ τ_u < 0, is work about to be
//               done on it → brake; otherwise motor — the brake wall of L1041, which holds while
//               the user pushes in and lets go the instant the force reverses. [I]
// Units: rad, rad/s, rad/s², N·m (a prismatic axis: m, m/s, m/s², N).

#include <string>

namespace haptic::engine {

// ---------------------------------------------------------------------------------------------
// Element laws (the torque the element applies to the joint).

/// Viscous damper, τ = −B q̇ (eq. 4.7, b_b = K_b K_v). B ≥ 0. Unit: N·m·s/rad.
constexpr double damper_torque(double B, double q_dot) { return -B * q_dot; }
/// Spring, τ = −K (q − q0) (eq. 4.8, k_b = K_b K_p). K ≥ 0. Unit: N·m/rad.
constexpr double spring_torque(double K, double q, double q0) { return -K * (q - q0); }
/// Mass, τ = −M q̈ (eq. 4.9, K_b K_a). M ≥ 0. Unit: kg·m².
constexpr double mass_torque(double M, double q_ddot) { return -M * q_ddot; }
/// One-sided wall occupying q > q_wall, a stiff spring while penetrating (L1041, the motor wall):
/// τ = −K_w (q − q_wall) for q > q_wall, else 0. K_w ≥ 0. Unit: N·m/rad.
constexpr double wall_torque(double K_w, double q, double q_wall) {
  return q > q_wall ? -K_w * (q - q_wall) : 0.0;
}

// ---------------------------------------------------------------------------------------------
// The split.

/// One axis' actuator commands.
struct HybridSplit {
  double motor = 0.0;  // Signed motor torque. Unit: N·m.
  double brake = 0.0;  // Brake clamping torque b ≥ 0. Unit: N·m.
};

struct HybridRuleParams {
  double brake_limit = 0.0;       // b_max > 0: the brake's largest clamping torque. Unit: N·m.
  double stick_velocity = 1e-3;   // v_s > 0: below it the user's torque decides. Unit: rad/s.

  /// Empty when usable; otherwise one message naming the bad parameter.
  std::string validate() const;
};

/// The rule above for the desired joint torque `tau`, the joint velocity `q_dot` and the user's
/// torque `tau_user` on the joint (0 when unknown: the motor then takes τ near rest).
/// With the brake slipping, the joint receives motor − b sgn(q̇) = tau (until b_max).
HybridSplit split_hybrid(double tau, double q_dot, double tau_user, const HybridRuleParams& params);

/// The brake's torque on a slipping joint, −b sgn(q̇) (L963, Fig. 4.8). Unit: N·m.
double brake_joint_torque(double brake, double q_dot);

/// Energy-bounded release [I], for a hybrid element that stores energy (a spring, a mass): the
/// motor may give back no more than the brake and the motor have taken in. The document's rule
/// releases "according to the constitutive equation"; sampled and held, that returns slightly
/// more than the brake absorbed (the held release torque leads the unloading motion, the held
/// brake torque lags the loading). This keeps the account exact for held commands: over each
/// tick a held brake b absorbs b |Δq| and a held motor m delivers m Δq.
class EnergyBoundedRelease {
 public:
  /// Call once per tick with the axis' position q (rad) and velocity q̇ (rad/s), the split the
  /// rule gave, and the tick dt (s); returns it with the motor's release limited so that its
  /// predicted delivery over the next tick, m q̇ dt, does not exceed half the stored energy (the
  /// margin covers the prediction's error while the tick's displacement |Δq| < 2 |q̇| dt).
  HybridSplit limit(const HybridSplit& split, double q, double q_dot, double dt);
  /// Energy taken in and not yet given back. Unit: J.
  double stored() const { return stored_; }

 private:
  double stored_ = 0.0;
  double last_q_ = 0.0;
  HybridSplit last_{};
  bool primed_ = false;
};

}  // namespace haptic::engine
