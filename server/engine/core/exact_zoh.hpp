#pragma once
// The exact zero-order-hold discretization of a small linear time-invariant system, shared by
// the study's linear cases (lab/study) and the sampled wall's analysis of a device with an
// actuator lag (engine/scene/impedance). Off the loop.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>

namespace haptic::engine {

/// Exact ZOH for a small linear time-invariant system ẋ = A x + b u with u held over the step:
/// x₁ = Φ x₀ + Γ u, Φ = e^{Ah}, Γ = ∫₀ʰ e^{As} ds b (scaling and squaring of a Taylor series on the
/// augmented matrix [[A, b], [0, 0]]).
template <std::size_t N>
struct ZohStep {
  std::array<std::array<double, N>, N> phi{};
  std::array<double, N> gamma{};
};

template <std::size_t N>
ZohStep<N> exact_zoh(const std::array<std::array<double, N>, N>& a, const std::array<double, N>& b,
                     double h) {
  constexpr std::size_t M = N + 1;
  using Matrix = std::array<std::array<double, M>, M>;
  Matrix m{};  // h · [[A, b], [0, 0]]
  double norm = 0.0;
  for (std::size_t i = 0; i < N; ++i) {
    for (std::size_t j = 0; j < N; ++j) m[i][j] = a[i][j] * h;
    m[i][N] = b[i] * h;
    double row = 0.0;
    for (std::size_t j = 0; j < M; ++j) row += std::abs(m[i][j]);
    norm = std::max(norm, row);
  }
  int squarings = 0;  // scale so that ||m|| ≤ 1/2, where 20 Taylor terms are exact to rounding
  while (norm > 0.5) {
    norm *= 0.5;
    ++squarings;
  }
  const double scale = std::ldexp(1.0, -squarings);
  for (auto& row : m) {
    for (double& v : row) v *= scale;
  }
  auto multiply = [](const Matrix& x, const Matrix& y) {
    Matrix out{};
    for (std::size_t i = 0; i < M; ++i) {
      for (std::size_t k = 0; k < M; ++k) {
        for (std::size_t j = 0; j < M; ++j) out[i][j] += x[i][k] * y[k][j];
      }
    }
    return out;
  };
  Matrix result{}, term{};
  for (std::size_t i = 0; i < M; ++i) result[i][i] = term[i][i] = 1.0;
  for (int k = 1; k <= 20; ++k) {
    term = multiply(term, m);
    for (std::size_t i = 0; i < M; ++i) {
      for (std::size_t j = 0; j < M; ++j) {
        term[i][j] /= k;
        result[i][j] += term[i][j];
      }
    }
  }
  for (int s = 0; s < squarings; ++s) result = multiply(result, result);
  ZohStep<N> step;
  for (std::size_t i = 0; i < N; ++i) {
    for (std::size_t j = 0; j < N; ++j) step.phi[i][j] = result[i][j];
    step.gamma[i] = result[i][N];
  }
  return step;
}

}  // namespace haptic::engine
