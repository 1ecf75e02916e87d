#include "engine/control/state_estimator.hpp"
#include "engine/core/parameter_checks.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <sstream>

namespace haptic::engine {
namespace {

Matrix2 operator*(const Matrix2& a, const Matrix2& b) {
  return {a.m00 * b.m00 + a.m01 * b.m10, a.m00 * b.m01 + a.m01 * b.m11,
          a.m10 * b.m00 + a.m11 * b.m10, a.m10 * b.m01 + a.m11 * b.m11};
}
Matrix2 operator+(const Matrix2& a, const Matrix2& b) {
  return {a.m00 + b.m00, a.m01 + b.m01, a.m10 + b.m10, a.m11 + b.m11};
}
Matrix2 operator*(double s, const Matrix2& a) {
  return {s * a.m00, s * a.m01, s * a.m10, s * a.m11};
}
Vector2 operator*(const Matrix2& a, const Vector2& x) {
  return {a.m00 * x.v0 + a.m01 * x.v1, a.m10 * x.v0 + a.m11 * x.v1};
}
Matrix2 transpose(const Matrix2& a) { return {a.m00, a.m10, a.m01, a.m11}; }
Matrix2 outer(const Vector2& a, const Vector2& b) {
  return {a.v0 * b.v0, a.v0 * b.v1, a.v1 * b.v0, a.v1 * b.v1};
}
constexpr Matrix2 kIdentity{1.0, 0.0, 0.0, 1.0};

double max_abs(const Matrix2& a) {
  return std::max({std::abs(a.m00), std::abs(a.m01), std::abs(a.m10), std::abs(a.m11)});
}

/// Solves M P + P Mᵀ + N = 0 for symmetric P (N symmetric): three linear equations in
/// (p00, p01, p11), by Cramer's rule.
Matrix2 solve_lyapunov(const Matrix2& M, const Matrix2& N) {
  // Rows: (0,0), (0,1), (1,1) entries of M P + P Mᵀ = −N.
  const double a[3][3] = {{2.0 * M.m00, 2.0 * M.m01, 0.0},
                          {M.m10, M.m00 + M.m11, M.m01},
                          {0.0, 2.0 * M.m10, 2.0 * M.m11}};
  const double rhs[3] = {-N.m00, -0.5 * (N.m01 + N.m10), -N.m11};
  const auto det3 = [](const double m[3][3]) {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  };
  const double d = det3(a);
  double p[3];
  for (int col = 0; col < 3; ++col) {
    double m[3][3];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) m[r][c] = c == col ? rhs[r] : a[r][c];
    }
    p[col] = det3(m) / d;
  }
  return {p[0], p[1], p[1], p[2]};
}

/// Left side of A P + P Aᵀ − P Cᵀ R⁻¹ C P + W.
Matrix2 riccati_left_side(const Matrix2& A, const Vector2& C, const Matrix2& W, double R,
                          const Matrix2& P) {
  const Vector2 PC = P * Vector2{C.v0, C.v1};
  return A * P + P * transpose(A) + (-1.0 / R) * outer(PC, PC) + W;
}

}  // namespace

std::string StateEstimatorParams::validate() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  const auto non_negative = [](double v) { return std::isfinite(v) && v >= 0.0; };
  if (!positive(inertia)) return bad_parameter("inertia", "must be finite and > 0", inertia);
  if (!non_negative(damping)) return bad_parameter("damping", "must be finite and >= 0", damping);
  if (!positive(process_noise_position)) {
    return bad_parameter("process_noise_position", "must be finite and > 0", process_noise_position);
  }
  if (!non_negative(process_noise_torque)) {
    return bad_parameter("process_noise_torque", "must be finite and >= 0", process_noise_torque);
  }
  if (!positive(measurement_noise)) {
    return bad_parameter("measurement_noise", "must be finite and > 0", measurement_noise);
  }
  if (!non_negative(friction_coulomb)) {
    return bad_parameter("friction_coulomb", "must be finite and >= 0", friction_coulomb);
  }
  if (!positive(friction_velocity)) {
    return bad_parameter("friction_velocity", "must be finite and > 0", friction_velocity);
  }
  if (!positive(torque_limit)) return bad_parameter("torque_limit", "must be finite and > 0", torque_limit);
  if (!positive(sample_period)) {
    return bad_parameter("sample_period", "must be finite and > 0", sample_period);
  }
  return {};
}

EstimatorModel estimator_model(const StateEstimatorParams& p) {
  const double b2 = 1.0 / p.inertia;  // B₂ = 1/J (L3088)
  EstimatorModel m;
  m.A = {0.0, 1.0, 0.0, -p.damping / p.inertia};  // control canonical form (L3084)
  m.B = {0.0, b2};
  m.C = {1.0, 0.0};
  m.G = {1.0, 0.0, 0.0, b2};  // w2 enters as noise on the torque u (L3107–3113)
  m.Q = {p.process_noise_position, 0.0, 0.0, p.process_noise_torque};
  m.R = p.measurement_noise;
  return m;
}

RiccatiSolution solve_filter_riccati(const Matrix2& A, const Vector2& C, const Matrix2& W,
                                     double R) {
  RiccatiSolution out;
  // Ackermann: L₀ = φ(A) O⁻¹ [0, 1]ᵀ with φ(s) = (s + ω₀)², O = [C; C A].
  const double w0 = 1.0 + 2.0 * (std::abs(A.m00) + std::abs(A.m01) + std::abs(A.m10) +
                                 std::abs(A.m11));
  const Matrix2 phi = A * A + (2.0 * w0) * A + (w0 * w0) * kIdentity;
  const Vector2 CA{C.v0 * A.m00 + C.v1 * A.m10, C.v0 * A.m01 + C.v1 * A.m11};
  const double det_O = C.v0 * CA.v1 - C.v1 * CA.v0;
  if (det_O == 0.0 || !std::isfinite(det_O)) return out;  // not observable
  const Vector2 last_column_of_O_inv{-C.v1 / det_O, C.v0 / det_O};
  Vector2 L = phi * last_column_of_O_inv;

  Matrix2 P;
  for (int k = 1; k <= 100; ++k) {
    // A_k = A − L C; solve A_k P + P A_kᵀ + W + L R Lᵀ = 0; L ← P Cᵀ / R.
    const Matrix2 Ak = A + (-1.0) * outer(L, C);
    const Matrix2 next = solve_lyapunov(Ak, W + R * outer(L, L));
    const double change = max_abs(next + (-1.0) * P);
    P = next;
    L = (1.0 / R) * P * Vector2{C.v0, C.v1};
    out.iterations = k;
    if (change <= 1e-14 * std::max(1.0, max_abs(P))) {
      out.converged = true;
      break;
    }
  }
  out.P = P;
  out.L = L;
  out.residual = max_abs(riccati_left_side(A, C, W, R, P));
  return out;
}

std::array<std::complex<double>, 2> eigenvalues(const Matrix2& M) {
  const double half_trace = 0.5 * (M.m00 + M.m11);
  const double det = M.m00 * M.m11 - M.m01 * M.m10;
  const std::complex<double> root = std::sqrt(std::complex<double>(half_trace * half_trace - det));
  return {half_trace - root, half_trace + root};
}

DiscreteEstimator discretize_zoh(const Matrix2& M, const Vector2& b_u, const Vector2& b_q,
                                 double T) {
  // Scale so that ‖M h‖∞ ≤ 0.5, sum the series for Φ(h) = e^{Mh} and Ψ(h) = ∫₀ʰ e^{Ms} ds, then
  // double: Φ(2h) = Φ(h)², Ψ(2h) = (I + Φ(h)) Ψ(h).
  const double norm = std::max(std::abs(M.m00) + std::abs(M.m01),
                               std::abs(M.m10) + std::abs(M.m11)) * T;
  int squarings = 0;
  double h = T;
  while (norm / static_cast<double>(1 << squarings) > 0.5 && squarings < 30) ++squarings;
  h = T / static_cast<double>(1 << squarings);
  const Matrix2 Mh = h * M;
  Matrix2 term = kIdentity;  // (Mh)^k / k!
  Matrix2 phi = kIdentity;
  Matrix2 psi = h * kIdentity;  // h Σ (Mh)^k / (k+1)!
  for (int k = 1; k <= 20; ++k) {
    term = (1.0 / k) * (term * Mh);
    phi = phi + term;
    psi = psi + (h / (k + 1)) * term;
  }
  for (int s = 0; s < squarings; ++s) {
    psi = (kIdentity + phi) * psi;
    phi = phi * phi;
  }
  return {phi, psi * b_u, psi * b_q};
}

StateEstimator::StateEstimator(const StateEstimatorParams& params)
    : params_(params), model_(estimator_model(params)) {
  assert(params.validate().empty());
  const Matrix2 W = model_.G * model_.Q * transpose(model_.G);
  riccati_ = solve_filter_riccati(model_.A, model_.C, W, model_.R);
  assert(riccati_.converged);
  error_dynamics_ = model_.A + (-1.0) * outer(riccati_.L, model_.C);
  discrete_ = discretize_zoh(error_dynamics_, model_.B, riccati_.L, params.sample_period);
}

double StateEstimator::friction() const {
  return params_.friction_coulomb *
         std::clamp(x_.v1 / params_.friction_velocity, -1.0, 1.0);  // Fig. 6.18(b)
}

double StateEstimator::net_torque(double command, double user_torque) const {
  return std::clamp(command, -params_.torque_limit, params_.torque_limit) + user_torque -
         friction();  // Fig. 6.19
}

void StateEstimator::update(double q_measured, double user_torque, double command) {
  const double u = net_torque(command, user_torque);
  const Vector2 free = discrete_.Phi * x_;
  x_ = {free.v0 + discrete_.Gamma_u.v0 * u + discrete_.Gamma_q.v0 * q_measured,
        free.v1 + discrete_.Gamma_u.v1 * u + discrete_.Gamma_q.v1 * q_measured};
}

}  // namespace haptic::engine
