#pragma once
// Contact impedances for the scene: a discrete spring-damper-mass law on a penetration, a virtual
// coupling between device and proxy, the passivity bound and sampled stability margin of a wall,
// and the tangent-plane local model.
//
// Sign conventions. A contact is described by its penetration d (Unit: m): the depth of the tool
// point T below a surface along the surface's outward unit normal n, d > 0 in contact. The
// impedance's force f (Unit: N) is the magnitude along +n of the force on the tool: f > 0 pushes
// the tool out. So for a wall, F_T_W = f n.
//
// Sources: Monasterio-Huelin, Gutiérrez, Larraga, "Introduction to Haptic Systems" (document 000),
// eqs. 7.1, 8.9–8.17; Madill 1998 ch. 2, eq. 2.6 (Colgate & Schenkel's passivity bound);
// Colgate, Stanley & Brown 1995 (virtual coupling); Russo 1990 ch. 5 (tangent-plane model);
// Gillespie & Cutkosky 1996 (the sampled wall on a mass-damper).
//
// Everything called per tick (ImpedanceFilter::update, VirtualCoupling::force,
// TangentPlaneContact::update) allocates nothing and never throws. Constructors, validators and
// the analysis functions run off the loop.

#include <array>
#include <complex>
#include <cstddef>
#include <cstdint>
#include <string>

#include "engine/control/dc_motor_control.hpp"
#include "engine/core/vec3.hpp"

namespace haptic::engine {

// ---------------------------------------------------------------------------------------------
// The discrete impedance law.

/// f = K d + B ḋ + M d̈ along the contact normal (000 eq. 8.1 for the spring-damper, eq. 7.1 for
/// the mass term).
struct ImpedanceParams {
  double stiffness = 0.0;  // K. Unit: N/m. Finite, >= 0.
  double damping = 0.0;    // B. Unit: N·s/m. Finite, >= 0.
  double mass = 0.0;       // M. Unit: kg. Finite, >= 0.
};

/// How the continuous law is turned into a difference equation on the samples d(k) = d(kT).
enum class ImpedanceDiscretization {
  /// ḋ ≈ (d(k) − d(k−1))/T, d̈ ≈ (d(k) − 2d(k−1) + d(k−2))/T² (000 eqs. 8.14–8.16). First order.
  kBackwardDifference,
  /// The exact ZOH discretization of the spring-damper made causal with a one-sample delay
  /// (000 eqs. 8.9–8.12), generalised from the torsion spring to a penetration; mass term as in
  /// kBackwardDifference.
  kExactZoh,
  /// The bilinear transform s → (2/T)(z − 1)/(z + 1) of K + B s; mass term by the second-order
  /// backward formula. Second order in the open loop, but its damper's pole at z = −1 is pushed
  /// just outside the unit circle by a ZOH device for every B > 0 (|z| = 1.00024 for B = 5 N·s/m
  /// on document 001's device at 1 kHz): a wall with B > 0 rings up at the Nyquist frequency.
  /// sampled_wall_margin reports it; use it for analysis, or with B = 0.
  kTustin,
};

/// How a contact turns penetration into force along the normal (and an orientation spring its
/// rotation error into torque, per axis).
enum class ContactLaw : std::uint8_t {
  /// F = max(0, K d − B v·n) with the device's measured velocity v (the default).
  kVelocity,
  /// F = K d + B ḋ + M d̈ on the sampled penetration, by backward differences (000 eq. 8.15).
  kBackwardDifference,
  /// The exact zero-order-hold form of 000 eq. 8.11 (weights a1 + a2 = K, eq. 8.12).
  kExactZoh,
  /// Tustin's bilinear form (unstable with B > 0 on a real device: see docs/scene.md).
  kTustin,
};

/// The ImpedanceDiscretization of a discrete law; kVelocity maps to the backward difference, the
/// discrete law closest to it (how the stability report models it).
ImpedanceDiscretization discretization_of(ContactLaw law);

/// Largest number of past samples any form keeps (kTustin with a mass uses d(k−3)).
inline constexpr std::size_t kImpedanceHistory = 3;

/// The per-tick weights of one law, computed once (off the loop) from K, B, M and T:
///   f(k) = Σ_{i=0..3} lag[i] d(k − i) + velocity_gain · v(k),
/// where v(k) is the trapezoidal (Tustin) velocity v(k) = −v(k−1) + (2/T)(d(k) − d(k−1)), used by
/// kTustin only (velocity_gain = 0 otherwise). lag[0]: Unit N/m; others likewise.
struct ImpedanceWeights {
  std::array<double, kImpedanceHistory + 1> lag{};  // Unit: N/m.
  double velocity_gain = 0.0;                       // Unit: N·s/m.
  double period = 0.0;                              // T. Unit: s.
};

/// The weights of each form (000 eq. numbers in impedance.cpp). params must be valid for T
/// (validate_impedance). The exact form reuses exact_delayed_coefficients (000 eq. 8.12) for
/// K > 0, B > 0; its limits B → 0 (a1 = K, a2 = 0) and K → 0 (a1 = −a2 = B/T, the pure damper's
/// exact ZOH inverse) are the backward-difference weights, so the form is continuous in K and B.
ImpedanceWeights impedance_weights(const ImpedanceParams& params,
                                   ImpedanceDiscretization discretization, double T);

/// "" if params and T are usable, else one message naming the bad field and its value
/// ("damping: must be finite and >= 0, got -1"). T: Unit s, finite, > 0.
std::string validate_impedance(const ImpedanceParams& params, double T);

/// A per-contact discrete impedance: a small stateful filter holding the previous samples.
/// Difference equations (d(k) the penetration at tick k; T the period):
///   backward:  f(k) = K d(k) + B (d(k) − d(k−1))/T + M (d(k) − 2 d(k−1) + d(k−2))/T²
///   exact ZOH: f(k) = a1 d(k) + a2 d(k−1) + M (d(k) − 2 d(k−1) + d(k−2))/T²,
///              a1 = K / (1 − e^{−KT/B}), a2 = −K e^{−KT/B} / (1 − e^{−KT/B}), a1 + a2 = K
///              (000 eqs. 8.11–8.12: f(k) is exactly the force that, held over [(k−1)T, kT),
///              moves the continuous spring-damper from d(k−1) to d(k), eq. 8.9)
///   Tustin:    v(k) = −v(k−1) + (2/T)(d(k) − d(k−1)),
///              f(k) = K d(k) + B v(k) + M (2 d(k) − 5 d(k−1) + 4 d(k−2) − d(k−3))/T².
/// The bilinear transform of M s² would put a double pole at z = −1, where any initial error
/// grows linearly; hence the mass's second-order backward formula. Tustin's velocity has its pole
/// at z = −1 (undamped): an initial velocity that is wrong by δ leaves a ±δ ripple at the Nyquist
/// rate for the whole contact, so reset() with the measured velocity.
/// f is not clamped: a surface that may only push clamps f at 0 itself.
class ImpedanceFilter {
 public:
  /// A law that gives zero force (all weights zero).
  ImpedanceFilter() = default;
  explicit ImpedanceFilter(const ImpedanceWeights& weights) : weights_(weights) {}
  ImpedanceFilter(const ImpedanceParams& params, ImpedanceDiscretization discretization, double T)
      : ImpedanceFilter(impedance_weights(params, discretization, T)) {}

  /// Starts a contact. d_previous is the penetration at the sample before the next update (m;
  /// 000 eq. 8.11's initial condition θ_V(k0) = 0 is the default), rate_previous and
  /// acceleration_previous its rate ḋ (m/s) and acceleration d̈ (m/s²) then; older samples are
  /// extrapolated from them, d(k−1−j) = d_previous − j T ḋ + (j T)² d̈ / 2, and Tustin's velocity
  /// state is set to ḋ.
  void reset(double d_previous = 0.0, double rate_previous = 0.0,
             double acceleration_previous = 0.0);

  /// Takes another filter's past samples, keeping its own weights: a new version of a law (a
  /// parameter change) continues from the old one's history instead of restarting the contact.
  void copy_history_from(const ImpedanceFilter& other) {
    history_ = other.history_;
    velocity_ = other.velocity_;
  }

  /// The force f(k) (Unit: N, > 0 pushes out) for the penetration d(k) (Unit: m); remembers d(k).
  double update(double d) {
    const auto& w = weights_.lag;
    const double T = weights_.period;
    // Tustin's trapezoidal velocity; computed for every form (it costs less than a branch).
    const double v = T > 0.0 ? -velocity_ + (2.0 / T) * (d - history_[0]) : 0.0;
    const double f = w[0] * d + w[1] * history_[0] + w[2] * history_[1] + w[3] * history_[2] +
                     weights_.velocity_gain * v;
    history_[2] = history_[1];
    history_[1] = history_[0];
    history_[0] = d;
    velocity_ = v;
    return f;
  }

  const ImpedanceWeights& weights() const { return weights_; }
  /// The last penetration given to update (or reset). Unit: m.
  double previous_penetration() const { return history_[0]; }

 private:
  ImpedanceWeights weights_;
  std::array<double, kImpedanceHistory> history_{};  // d(k−1), d(k−2), d(k−3). Unit: m.
  double velocity_ = 0.0;                            // Tustin v(k−1). Unit: m/s.
};

// ---------------------------------------------------------------------------------------------
// Passivity bound and sampled stability.

/// Colgate & Schenkel's passivity bound (Madill eq. 2.6): a virtual spring-damper (K, B) sampled
/// at period T with a zero-order hold, on a device with physical damping b, is passive iff
/// b > K T / 2 + |B|. Returns that minimum b. K: Unit N/m; B: Unit N·s/m; T: Unit s;
/// result: Unit N·s/m.
inline double colgate_bound(double K, double B, double T) {
  return K * T / 2.0 + (B < 0.0 ? -B : B);
}

/// A polynomial with real coefficients, lowest power first: p(z) = Σ c[i] z^i, i <= degree.
struct Polynomial {
  /// A wall law (degree ≤ 4) on the device (2) behind up to kMaxDelayTicks ticks of delay.
  static constexpr int kMaxDelayTicks = 100;
  static constexpr int kMaxDegree = 8 + kMaxDelayTicks;
  std::array<double, kMaxDegree + 1> c{};
  int degree = 0;
};

/// All roots of p (degree >= 1, c[degree] != 0) by Aberth–Ehrlich iteration followed by Newton
/// polishing; roots[0 .. degree−1] are filled. Multiple roots come out to about sqrt(eps).
std::array<std::complex<double>, Polynomial::kMaxDegree> polynomial_roots(const Polynomial& p);

/// The Schur–Cohn–Jury test: whether every root of p lies strictly inside the unit circle.
/// Exact in its decisions up to round-off in the reflection coefficients (Jury 1964).
bool schur_stable(const Polynomial& p);

/// One axis of the device: m ẍ + b ẋ = F (the default device, Eom et al. eq. 5).
struct MassDamperDevice {
  double mass = 0.01;      // m. Unit: kg. > 0.
  double damping = 0.022;  // b. Unit: N·s/m. >= 0.
  /// τ_a: the force the device applies follows the command through 1/(1 + s τ_a) (an amplifier's
  /// or a motor's time constant, an identification's lag). Unit: s. >= 0; 0: none.
  double actuator_lag = 0.0;
};

/// The closed loop of a wall in contact on the device: the device sampled with a ZOH
/// (G(z) = N(z)/D(z), exact), the wall the filter f(k) = W(z) d(k) applied at once and held over
/// the next period, so the characteristic polynomial is D(z) Dc(z) + N(z) Nc(z) with
/// W(z) = Nc(z)/Dc(z). The device's exact step over T with x = bT/m, e = e^{−x},
/// φ = (1 − e)/x, g = (x − 1 + e)/x² gives
///   N(z) = (T²/m) (g z + φ² − e g),   D(z) = (z − 1)(z − e).
/// Linear: the wall is taken to stay in contact (it may pull). With `delay_ticks` = d the force
/// reaches the device d ticks after the reading it answers, W(z) z^{−d}, so the polynomial is
/// z^d D(z) Dc(z) + N(z) Nc(z) (d ≤ Polynomial::kMaxDelayTicks). A fractional d = n + f (an
/// identified delay, docs/identification.md) is n ticks and Thiran's first-order all-pass with
/// η = (1 − f)/(1 + f): z^n (z + η) D Dc + (η z + 1) N Nc. A device with an actuator lag τ_a is
/// sampled exactly too, from its state space (x, v, f) with ḟ = (F − f)/τ_a: Φ = e^{AT} and
/// Γ = ∫₀ᵀ e^{As} ds B, so D(z) = det(zI − Φ) (cubic) and N(z) = C adj(zI − Φ) Γ (quadratic).
Polynomial wall_characteristic_polynomial(const ImpedanceWeights& wall,
                                          const MassDamperDevice& device,
                                          double delay_ticks = 0.0);

/// What sampled_wall_margin reports.
struct SampledWallMargin {
  double max_pole_magnitude = 0.0;  // Largest |z| of the closed loop with the wall as given.
  bool stable = false;              // max_pole_magnitude < 1 (by the Jury test).
  /// The largest K' (B, M fixed) for which the loop is stable: the upper end of the first stable
  /// interval met scanning up from 1e-12 m/T² (for a wall on a free mass-damper the stable set is
  /// (0, K')); 0 if no K' is stable; +inf if none up to 1e12 N/m is unstable. Unit: N/m.
  double max_stable_stiffness = 0.0;
  double colgate_damping = 0.0;     // colgate_bound(K, B, T). Unit: N·s/m.
  bool passive = false;             // device damping > colgate_damping.
};

/// Stability margin of a virtual wall (params, discretization) on the device at period T (Unit: s),
/// behind `delay_ticks` ticks of delay, from the roots and the Jury test of
/// wall_characteristic_polynomial; K' by bisection to 1e-9 relative. Colgate's bound (and
/// `passive`) assume no delay. Off the loop.
SampledWallMargin sampled_wall_margin(const ImpedanceParams& wall,
                                      ImpedanceDiscretization discretization,
                                      const MassDamperDevice& device, double T,
                                      double delay_ticks = 0.0);

// ---------------------------------------------------------------------------------------------
// Virtual coupling (Colgate, Stanley & Brown 1995).

/// The coupling's spring and damper between the tool T and the proxy P.
struct VirtualCouplingParams {
  double stiffness = 0.0;  // K_c. Unit: N/m. Finite, >= 0.
  double damping = 0.0;    // B_c. Unit: N·s/m. Finite, >= 0.
};

/// A coupling chosen for a device, with what it gives the device–proxy mode.
struct VirtualCouplingDesign {
  VirtualCouplingParams gains;
  double natural_frequency = 0.0;  // sqrt(K_c / m). Unit: rad/s.
  double damping_ratio = 0.0;      // (b + B_c) / (2 sqrt(K_c m)). Unitless.
};

/// Chooses a passive coupling for a device of mass m (kg), damping b (N·s/m) at period T (s):
/// the coupling's damper takes damping_share ∈ [0, 1) of b, B_c = damping_share · b, and the
/// spring takes the rest of Colgate's budget (Madill eq. 2.6), scaled by margin ∈ (0, 1):
/// K_c = margin · 2 (b − B_c) / T, so b > K_c T / 2 + B_c holds with room (1 − margin).
/// The mass enters only the reported mode (the bound holds whatever the mass).
/// Requires m > 0, b > 0, T > 0; returns zero gains otherwise.
VirtualCouplingDesign design_virtual_coupling(double m, double b, double T,
                                              double damping_share = 0.5, double margin = 0.9);

/// The coupling as evaluated every tick, damper by backward difference (the implementation
/// Colgate's bound is stated for): with e(k) = p_WP(k) − p_WT(k),
///   F_T_W(k) = K_c e(k) + B_c (e(k) − e(k−1)) / T,
/// the force on the tool (the proxy receives −F_T_W).
class VirtualCoupling {
 public:
  VirtualCoupling() = default;
  VirtualCoupling(const VirtualCouplingParams& params, double T) : params_(params), period_(T) {}

  /// Starts the coupling with e(k−1) = e_previous (Unit: m; zero: proxy and tool together).
  void reset(const Vec3& e_previous = {}) { e_previous_ = e_previous; }

  /// F_T_W(k) from p_WT(k) and p_WP(k) (Unit: m). Unit: N.
  Vec3 force(const Vec3& p_WT, const Vec3& p_WP) {
    const Vec3 e = p_WP - p_WT;
    const Vec3 F = params_.stiffness * e + (params_.damping / period_) * (e - e_previous_);
    e_previous_ = e;
    return F;
  }

  const VirtualCouplingParams& params() const { return params_; }

 private:
  VirtualCouplingParams params_;
  double period_ = 1e-3;  // T. Unit: s.
  Vec3 e_previous_;       // e(k−1). Unit: m.
};

// ---------------------------------------------------------------------------------------------
// The tangent-plane local model (Russo 1990 ch. 5).

/// The local model a slow client sends: the plane nearest the tool, with a normal impedance that
/// only pushes and a tangential impedance about a reference point on the surface.
struct TangentPlane {
  Vec3 point_W;             // x_p, a point of the plane. Unit: m.
  Vec3 normal_W{0, 0, 1};   // n_p, unit outward normal (free space on +n_p). Unitless.
  Vec3 reference_W;         // r, the surface reference point of the tangential spring. Unit: m.
  ImpedanceParams normal;   // K_n (N/m), b_n (N·s/m), m_n (kg) along n_p.
  double tangential_stiffness = 0.0;  // K_t. Unit: N/m. Finite, >= 0.
  double tangential_damping = 0.0;    // b_t. Unit: N·s/m. Finite, >= 0.
};

/// "" if the plane is usable at period T (s), else one message naming the field and value:
/// finite points, |normal_W| within 1e-6 of 1, valid impedances.
std::string validate_tangent_plane(const TangentPlane& plane, double T);

struct TangentPlaneForce {
  Vec3 F_T_W;                // Unit: N.
  double penetration = 0.0;  // d = (x_p − p_WT)·n_p; > 0 in contact. Unit: m.
  bool in_contact = false;
};

/// The tangent-plane contact evaluated every tick. With d = (x_p − p_WT)·n_p (Russo ch. 5 writes
/// the distance (x − x_p)·n_p; its negative is our penetration) and, in contact (d > 0),
///   f_n = max(0, f(k)),  f(k) the ImpedanceFilter law of (K_n, b_n, m_n) on d,
///   e_t = (I − n_p n_pᵀ)(p_WT − r),  v_t = (I − n_p n_pᵀ) v_WT,
///   F_T_W = f_n n_p − K_t e_t − b_t v_t;
/// out of contact F_T_W = 0. The normal filter is reset at each contact start with the previous
/// penetration and the measured normal velocity; a new plane while in contact re-seeds the filter
/// with the previous tool position's penetration under the new plane, so a plane update never
/// shows up as a velocity spike.
class TangentPlaneContact {
 public:
  /// T: Unit s, > 0.
  TangentPlaneContact(ImpedanceDiscretization discretization, double T)
      : discretization_(discretization), period_(T) {}

  /// Adopts a new plane (valid per validate_tangent_plane). Computes the filter's weights (a few
  /// exp calls) and allocates nothing, so it may run on the loop when a plane arrives.
  void set_plane(const TangentPlane& plane);

  /// The force for the tool at p_WT (m) moving at v_WT (m/s). No plane set: zero force.
  TangentPlaneForce update(const Vec3& p_WT, const Vec3& v_WT);

  /// Forgets the contact (the next penetration starts a new one).
  void reset() { in_contact_ = false; has_previous_ = false; }

  const TangentPlane& plane() const { return plane_; }

 private:
  ImpedanceDiscretization discretization_;
  double period_;
  TangentPlane plane_;
  ImpedanceFilter normal_filter_;
  bool has_plane_ = false;
  bool in_contact_ = false;
  bool has_previous_ = false;
  bool plane_changed_ = false;
  Vec3 p_previous_W_;  // p_WT at the previous update. Unit: m.
};

}  // namespace haptic::engine
