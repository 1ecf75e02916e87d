#pragma once
// The non-linear state estimator of Madill 1998, §6.3 (L3061–3290, Figs. 6.12 and 6.19), for one
// joint of the five-bar (the axial joint q1 by default).
//
// Continuous model (eq. 6.6, L3082–3125), x = [q, q̇] (rad, rad/s):
//   ẋ = A x + B u + G w,  q_m = C x + v,   A = [[0, 1], [0, −B_v/J]],  B = [0, 1/J],
//   C = [1, 0],  G = diag(1, 1/J),  Q = E[w wᵀ] = diag(1, 41.6),  R = E[v²] = 0.1.
// Stationary Kalman gain L = P Cᵀ R⁻¹, P the stabilizing solution of the filter algebraic Riccati
// equation A P + P Aᵀ − P Cᵀ R⁻¹ C P + G Q Gᵀ = 0 (L3131); the thesis prints L = [14.4, 99.2]
// (L3129). The estimator (L3133–3145):
//   dx̂/dt = (A − L C) x̂ + B u + L q_m,
//   u = sat(u_c, τ_d) + τ_u − u_f(q̇̂),  u_f = f0 sat(q̇̂ / v0)              (Fig. 6.19, L3215–3245)
// u_c the motor command, fed back saturated at the D/A limit τ_d = 7.23 N·m (L3236); τ_u the
// operator's torque at the joint (strain gauges, L3222); u_f the smooth friction model of
// Fig. 6.18(b) (f0 = 0.061 N·m, v0 = 0.03 rad/s) — a pure f0 sgn(q̇̂) limit-cycles under the
// hold (L3211).
//
// Discretization (the thesis does not state one; a choice): the exact zero-order-hold
// discretization of the estimator's linear part at the loop period T, with u and q_m held over
// the period, x̂[k+1] = Φ x̂[k] + Γ_u u[k] + Γ_q q_m[k], Φ = e^{(A − LC)T},
// [Γ_u Γ_q] = ∫₀ᵀ e^{(A − LC)s} ds [B L]. The friction is evaluated at the start of the period
// (from q̇̂[k]) and held with the rest of u. So the estimate used at tick k has seen the measurement
// of tick k−1 and the torque that acted over the last period.

#include <array>
#include <complex>
#include <string>

namespace haptic::engine {

/// A 2×2 matrix, row-major: [[m00, m01], [m10, m11]].
struct Matrix2 {
  double m00 = 0.0, m01 = 0.0, m10 = 0.0, m11 = 0.0;
};

/// A 2-vector (a column, or C as a row).
struct Vector2 {
  double v0 = 0.0, v1 = 0.0;
};

/// Parameters of one joint's estimator. Defaults: Madill's axial joint.
struct StateEstimatorParams {
  /// J. Unit: kg·m². > 0. 1/4.9016, the unrounded value behind A and B as printed (L3088);
  /// Table 5.4 rounds it to 0.204.
  double inertia = 1.0 / 4.9016;
  /// B_v. Unit: N·m·s/rad. >= 0. 0.0565 · J, the value behind A₂₂ = −0.0565 as printed (L3086);
  /// Table 5.4's 0.012 is this rounded (0.012 / 0.204 would give A₂₂ = −0.0588).
  double damping = 0.0565 / 4.9016;
  // Design weights (L3125); the thesis gives no units. As spectral densities of white noise:
  double process_noise_position = 1.0;  // Q₁₁, of w1 (rad/s, on q̇ = ...). Unit: rad²/s. > 0.
  double process_noise_torque = 41.6;   // Q₂₂, of w2 (N·m, on the torque u). Unit: N²·m²·s. >= 0.
  double measurement_noise = 0.1;       // R, of v (rad, on q_m). Unit: rad²·s. > 0.
  double friction_coulomb = 0.061;      // f0, hand-tuned (L2675, L3166). Unit: N·m. >= 0.
  double friction_velocity = 0.03;      // v0 of Fig. 6.18(b) (L3229). Unit: rad/s. > 0.
  double torque_limit = 7.23;           // τ_d = K_m K_a V_a (L3236–3244). Unit: N·m. > 0.
  double sample_period = 1e-3;          // T, the loop period (L3190). Unit: s. > 0.

  /// Empty when usable, otherwise one message naming the first bad parameter
  /// ("measurement_noise: must be finite and > 0, got 0").
  std::string validate() const;
};

/// The continuous model of eq. 6.6 as the thesis builds it (L3082–3125).
struct EstimatorModel {
  Matrix2 A;         // Unit: [[0, 1], [0, 1/s]].
  Vector2 B;         // [0, 1/J]. Unit: 1/(kg·m²).
  Vector2 C;         // [1, 0] (a row).
  Matrix2 G;         // diag(1, 1/J).
  Matrix2 Q;         // diag(Q₁₁, Q₂₂).
  double R = 0.0;    // Unit: rad²·s (see StateEstimatorParams).
};

EstimatorModel estimator_model(const StateEstimatorParams& params);

/// The stabilizing solution of A P + P Aᵀ − P Cᵀ R⁻¹ C P + W = 0 and its gain L = P Cᵀ R⁻¹.
struct RiccatiSolution {
  Matrix2 P;             // Error covariance. Symmetric, positive semi-definite.
  Vector2 L;             // Kalman gain. Unit: [1/s, 1/s²].
  int iterations = 0;    // Newton–Kleinman iterations taken.
  double residual = 0.0; // Largest |entry| of the equation's left side at P.
  bool converged = false;
};

/// Newton–Kleinman on the filter Riccati equation (each step a 2×2 Lyapunov equation solved in
/// closed form), started from an observer gain that puts both poles of A − L₀C at −ω₀ (Ackermann;
/// ω₀ = 1 + 2 Σ|A_ij|, any stabilizing start converges). Needs (A, C) observable, W ⪰ 0 with
/// (A, W^½) controllable on the imaginary axis, R > 0. Allocates nothing.
RiccatiSolution solve_filter_riccati(const Matrix2& A, const Vector2& C, const Matrix2& W,
                                     double R);

/// Eigenvalues of a 2×2 matrix (the estimator's poles when given A − LC). Unit: that of M.
std::array<std::complex<double>, 2> eigenvalues(const Matrix2& M);

/// Exact zero-order-hold discretization of ẋ = M x + b_u u + b_q q over a period T:
/// Φ = e^{MT}, Γ = ∫₀ᵀ e^{Ms} ds b (Taylor series with scaling and squaring).
struct DiscreteEstimator {
  Matrix2 Phi;
  Vector2 Gamma_u;  // Unit: rad per N·m, rad/s per N·m.
  Vector2 Gamma_q;  // Dimensionless, 1/s.
};
DiscreteEstimator discretize_zoh(const Matrix2& M, const Vector2& b_u, const Vector2& b_q,
                                 double T);

/// The estimator of Fig. 6.19 at period T. Construct off the loop (it solves the Riccati
/// equation); update() is a few multiplications.
class StateEstimator {
 public:
  explicit StateEstimator(const StateEstimatorParams& params = {});

  /// Starts from x̂ = [q, q̇].
  void reset(double q, double q_dot = 0.0) { x_ = {q, q_dot}; }

  /// q̂ at this tick. Unit: rad.
  double position() const { return x_.v0; }
  /// q̇̂ at this tick. Unit: rad/s.
  double velocity() const { return x_.v1; }

  /// u_f = f0 sat(q̇̂ / v0) at this tick (Fig. 6.18(b)). Unit: N·m.
  double friction() const;

  /// u = sat(u_c, τ_d) + τ_u − u_f(q̇̂) (Fig. 6.19). command: u_c, user_torque: τ_u. Unit: N·m.
  double net_torque(double command, double user_torque) const;

  /// Advances the estimate by one period with this tick's measurement q_m (rad), the operator's
  /// torque τ_u (N·m) and the command u_c (N·m) that will be held over the period.
  void update(double q_measured, double user_torque, double command);

  const StateEstimatorParams& params() const { return params_; }
  const EstimatorModel& model() const { return model_; }
  const RiccatiSolution& riccati() const { return riccati_; }
  /// L. Unit: [1/s, 1/s²].
  const Vector2& gain() const { return riccati_.L; }
  /// A − L C.
  const Matrix2& error_dynamics() const { return error_dynamics_; }
  const DiscreteEstimator& discrete() const { return discrete_; }

 private:
  StateEstimatorParams params_;
  EstimatorModel model_;
  RiccatiSolution riccati_;
  Matrix2 error_dynamics_;
  DiscreteEstimator discrete_;
  Vector2 x_;
};

}  // namespace haptic::engine
