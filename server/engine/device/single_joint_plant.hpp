#pragma once
// One joint of Madill's five-bar (Madill 1998, "Modelling and Control of a Haptic Interface: A
// Mechatronics Approach"): with the links dynamically decoupled and gravity balanced, each joint
// at haptic speeds is a SISO second-order plant (L2388), P(s) = 1 / (J s² + B s) (§5.3.2, L2583),
// plus Coulomb friction u_f = f sgn(q̇) (eq. 6.7, L3160):
//
//   (J + J_load) q̈ + B q̇ + f sgn(q̇) = sat(u, τ_d) + τ_ext(q, q̇)
//
// q is the joint angle (rad), q̇ its rate (rad/s); u the commanded motor torque (N·m), delivered
// through the D/A saturation τ_d (L3236); τ_ext the torque of whatever holds the link (the
// operator's hand, expressed at the joint); J_load the inertia the hand adds (its mass times the
// moment arm squared). The friction is CoulombViscousFriction::resisting (joint_friction.hpp):
// Karnopp's stick band keeps a joint at rest at rest while |applied| ≤ f.

#include <cstdint>
#include <string>

#include "engine/core/integrator.hpp"
#include "engine/device/joint_friction.hpp"

namespace haptic::engine {

/// Physical parameters of one joint. The defaults are the axial joint q1 (Table 5.4, L2617):
/// J = 0.204 kg·m² and B = 0.012 N·m·s/rad identified from ω_n and ζ; f = 0.088 N·m identified
/// from the r-intercept (eq. 5.6) — the hand-tuned 0.061 N·m of L2675 is what the estimator
/// assumes (StateEstimatorParams), so a simulated joint with these defaults differs from the
/// estimator's model as the real one did.
struct SingleJointParams {
  double inertia = 0.204;       // J. Unit: kg·m². > 0. Table 5.4, axial row.
  double damping = 0.012;       // B. Unit: N·m·s/rad. >= 0. Table 5.4, axial row.
  double coulomb = 0.088;       // f. Unit: N·m. >= 0. Table 5.4, axial row (eq. 5.6).
  double stick_velocity = 1e-4; // Karnopp band |q̇| < v_s treated as rest. Unit: rad/s. > 0.
                                // Not from the thesis: a simulation choice, 0.2 % of one count
                                // per millisecond (π/6000 rad / 1 ms ≈ 0.52 rad/s).
  double torque_limit = 7.23;   // τ_d = K_m K_a V_a = 0.373 · 3.87 · 5 (L3236–3244). Unit: N·m.
                                // > 0. The D/A saturates before the motor's 36.8 N·m peak.

  /// Empty when usable, otherwise one message naming the first bad parameter
  /// ("inertia: must be finite and > 0, got -1").
  std::string validate() const;

  /// The three rows of Table 5.4 (L2617–2621): J, B, f as identified; the rest as defaults.
  static SingleJointParams axial();       // x_e, q1: J 0.204, B 0.012, f 0.088
  static SingleJointParams vertical();    // y_e, q2: J 0.026, B 0.009, f 0.082
  static SingleJointParams horizontal();  // z_e, q0 (home position): J 0.733, B 0.045, f 0.125

  CoulombViscousFriction friction() const { return {coulomb, damping, stick_velocity}; }
};

struct SingleJointState {
  double q = 0.0;      // Joint angle. Unit: rad.
  double q_dot = 0.0;  // Joint rate. Unit: rad/s.
};

/// The joint plant, advanced one tick at a time under a torque command held over the tick
/// (zero-order hold, as the D/A does). Sub-steps and method come from IntegrationSettings; the
/// default RK4 × 10 at 1 ms puts the stiffest pole of interest (a tight grip's 72 N·m/rad on
/// 0.38 kg·m², ≈ 14 rad/s) at hλ ≈ 0.0014, far inside RK4's stability interval.
class SingleJointPlant {
 public:
  explicit SingleJointPlant(const SingleJointParams& params, const SingleJointState& initial = {},
                            const IntegrationSettings& integration = {});

  /// One tick of length dt (s) under command u (N·m, saturated at torque_limit) and the external
  /// torque external(q, q̇) -> N·m, re-evaluated at every stage. Not allocating.
  template <typename ExternalTorqueFn>
  void step(double u, double dt, ExternalTorqueFn&& external) {
    const double motor = saturate(u, params_.torque_limit);
    const CoulombViscousFriction friction = params_.friction();
    const double inv_inertia = 1.0 / (params_.inertia + load_inertia_);
    StateVector<2> x{state_.q, state_.q_dot};
    integrate_tick<1>(integration_, x, dt, [&](const StateVector<2>& s) {
      const double applied = motor + external(s[0], s[1]);
      // J q̈ = applied − (f sgn q̇ + B q̇), with the stick band of resisting().
      return StateVector<2>{s[1], (applied - friction.resisting(s[1], applied)) * inv_inertia};
    });
    state_ = {x[0], x[1]};
  }

  /// One tick with nothing holding the link.
  void step(double u, double dt) {
    step(u, dt, [](double, double) { return 0.0; });
  }

  /// Inertia that moves with the link besides its own (a hand's m_h l², l the moment arm).
  /// Unit: kg·m². >= 0.
  void set_load_inertia(double load_inertia) { load_inertia_ = load_inertia; }
  double load_inertia() const { return load_inertia_; }

  const SingleJointState& state() const { return state_; }
  void set_state(const SingleJointState& state) { state_ = state; }
  const SingleJointParams& params() const { return params_; }
  const IntegrationSettings& integration() const { return integration_; }

 private:
  SingleJointParams params_;
  SingleJointState state_;
  IntegrationSettings integration_;
  double load_inertia_ = 0.0;
};

}  // namespace haptic::engine
