#pragma once
// A discrete disturbance observer for one Cartesian axis (Eom, Suh, Yi, "A Design Method of Haptic
// Interface Controller Considering Transparency and Robust Stability", §2, Fig. 1, eqs. 3–5; after
// Umeno and Hori 1991, their ref. [5]).
//
// The axis is written as its nominal mass-damper plus an equivalent disturbance (eq. 3),
//   F = M̄ ẍ + B̄ ẋ + F_d,        P_n(s) = 1 / (M̄ s + B̄)                       (Fig. 1)
// where F is every force applied to the axis that the controller knows (the motors' and, through
// the handle's force measurement, the operator's), and F_d gathers the rest: the inertia mismatch,
// the coupling to the other axis, Coriolis terms and friction (eq. 4). The observer estimates
//   F̂_d = Q(s) [F − P_n^{-1}(s) ẋ],        Q(s) = 1 / (τ_q s + 1),  τ_q = 1 / ω_q
// and adds it to the command, u = F_ref + F̂_d, so that below ω_q the axis obeys
//   M̄ ẍ + B̄ ẋ = F_ref + F_h                                                  (eq. 5)
// (with a measured operator force F_h; the scene's force F_ref).
// Q is first order: P_n has relative degree one, so Q P_n^{-1} = (M̄ s + B̄)/(τ_q s + 1) is proper.
// The cut-off is chosen here (the document does not give it): ω_q = 2π · 80 Hz = 503 rad/s,
// well above the band of a hand's voluntary force (about 10 Hz, the reason for wall_design's w1),
// six times below the 1 ms loop's Nyquist rate π/T = 3142 rad/s. The inner loop's crossover is
// about ω_q M̄/M for a true mass M >= M̄ (at most 410 rad/s on the five-bar's workspace, where
// M >= 0.012 kg), which leaves about 55° of phase margin against the loop's 1.5 T delay (one
// sample plus the hold's T/2). With a first-order Q the residual mismatch below the cut-off is
// about ω (M − M̄)/(M̄ ω_q): the cut-off is a trade between that and the delay.
//
// Discretization at the tick period T (the loop holds each command over a tick):
//  - the nominal plant under a held force, exactly (step-invariant):
//      v_{k+1} = φ v_k + (1 − φ) F_k / B̄,   φ = e^{−B̄T/M̄},
//    so the force that explains the measured step from v_{k−1} to v_k is
//      F̃_{k−1} = g (v_k − φ v_{k−1}),   g = B̄ / (1 − φ)   (→ M̄/T as B̄ → 0),
//    P_n^{-1} inverted one tick late, the only causal way;
//  - the raw disturbance of tick k − 1, e_k = F_{k−1} − F̃_{k−1}, filtered by Q discretized
//    the same way, Q(z) = (1 − a) / (1 − a z^{-1}), a = e^{−T ω_q}:
//      F̂_d,k = a F̂_d,k−1 + (1 − a) e_k.
// For a device that is exactly the nominal plant e_k = 0 at every tick, so the observer changes
// nothing; a continuous design discretized term by term (M̄ s approximated by a held velocity)
// would not: its mass gain is off by about T ω_q / 2 (25 % at this cut-off), which the device
// would then show as a mass error at every frequency. F̂_d,k depends on v_k (through e_k) and on
// earlier ticks only: no algebraic loop with u_k. Constant size, no allocation; a few
// multiplications per tick.

#include <string>

namespace haptic::engine {

struct DisturbanceObserverParams {
  double nominal_mass = 0.01;      // M̄ (document §4: m = 0.01 kg). Unit: kg. > 0.
  double nominal_damping = 0.022;  // B̄ (document §4: b = 0.022 N·s/m). Unit: N·s/m. >= 0.
  double cutoff = 502.6548245743669;  // ω_q of Q(s) = 2π · 80 Hz (chosen, see above). Unit: rad/s.
  double sample_period = 1e-3;     // T (document §4: 1 ms). Unit: s. > 0.

  /// Empty when usable; otherwise one message naming the first bad parameter
  /// ("cutoff: must be finite and in (0, π / sample_period), got 5000"): ω_q must lie below the
  /// Nyquist rate.
  std::string validate() const;
};

/// One axis's observer. Per tick k: u_k = command(F_ref,k, v_k); apply u_k; then
/// update(F_k, v_k) with the force F_k actually applied over the tick (u_k after saturation, plus
/// the measured operator force).
class DisturbanceObserver {
 public:
  explicit DisturbanceObserver(const DisturbanceObserverParams& params);

  /// F̂_d,k = a F̂_d,k−1 + (1 − a)(F_{k−1} − g (v_k − φ v_{k−1})). velocity v_k: Unit m/s.
  /// Result: Unit N.
  double estimate(double velocity) const {
    const double raw = previous_force_ - g_ * (velocity - phi_ * previous_velocity_);
    return a_ * estimate_ + one_minus_a_ * raw;
  }

  /// u_k = F_ref,k + F̂_d,k: the force to command for the axis to behave as P_n under F_ref.
  /// Units: N, m/s -> N.
  double command(double force_reference, double velocity) const {
    return force_reference + estimate(velocity);
  }

  /// Ends tick k: remembers F̂_d,k, the force applied over the tick (N) and v_k (m/s).
  void update(double applied_force, double velocity) {
    estimate_ = estimate(velocity);
    previous_force_ = applied_force;
    previous_velocity_ = velocity;
  }

  /// At rest with nothing applied and nothing estimated (the state at construction).
  void reset() {
    estimate_ = 0.0;
    previous_force_ = 0.0;
    previous_velocity_ = 0.0;
  }

  /// The estimate as of the last update(). Unit: N.
  double last_estimate() const { return estimate_; }
  /// Q's pole a = e^{−T ω_q} and the nominal plant's φ = e^{−B̄T/M̄} (dimensionless).
  double filter_pole() const { return a_; }
  double nominal_pole() const { return phi_; }
  const DisturbanceObserverParams& params() const { return params_; }

 private:
  DisturbanceObserverParams params_;
  double phi_;          // e^{−B̄T/M̄}
  double g_;            // B̄ / (1 − φ). Unit: N·s/m.
  double a_;            // e^{−T ω_q}
  double one_minus_a_;
  double estimate_ = 0.0;           // F̂_d of the last tick. Unit: N.
  double previous_force_ = 0.0;     // F of the last tick. Unit: N.
  double previous_velocity_ = 0.0;  // v of the last tick. Unit: m/s.
};

}  // namespace haptic::engine
