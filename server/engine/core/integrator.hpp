#pragma once
// Fixed-step integrators shared by the plants. A plant's state is a fixed-size array laid out as
// [q_0 … q_{n−1}, q̇_0 … q̇_{n−1}, extra…]: the first `kPositions` entries are positions whose
// derivatives are the next `kPositions` entries (velocities); anything after them (a current, a
// filter state) is a first-order state. The right-hand side is a callable
// rhs(const State&) -> State returning dx/dt. Nothing here allocates.
//
// Which one to pick is a measured choice (docs/devices.md, "Integrators"): explicit Euler is the
// cheapest and gains energy on an undamped oscillator; semi-implicit (symplectic) Euler costs the
// same, keeps an undamped oscillator's energy bounded, and is first order; RK4 costs four
// evaluations and is fourth order, stable for hλ in (−2.78, 0] on a real pole; implicit Euler and
// the trapezoidal rule solve a small nonlinear system per step (Newton) and are stable for any
// step on a stable linear system — implicit Euler damping what it cannot resolve, the trapezoidal
// rule keeping an undamped oscillator's energy.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>
#include <utility>

namespace haptic::engine {

enum class Integrator : std::uint8_t {
  kExplicitEuler,      // x += h f(x)
  kSemiImplicitEuler,  // q̇ += h q̈(q, q̇); q += h q̇(new); extra states explicit
  kRk4,                // classical fourth-order Runge–Kutta
  kImplicitEuler,      // x₁ = x₀ + h f(x₁): first order, L-stable (damps what is stiff)
  kTrapezoidal,        // x₁ = x₀ + h (f(x₀) + f(x₁))/2: second order, A-stable, keeps a linear
                       // oscillator's energy
};

/// How a plant advances over one tick: `substeps` equal steps of the chosen method.
struct IntegrationSettings {
  Integrator method = Integrator::kRk4;
  std::uint32_t substeps = 10;
};

constexpr std::string_view integrator_name(Integrator method) {
  switch (method) {
    case Integrator::kExplicitEuler: return "explicit_euler";
    case Integrator::kSemiImplicitEuler: return "semi_implicit_euler";
    case Integrator::kRk4: return "rk4";
    case Integrator::kImplicitEuler: return "implicit_euler";
    case Integrator::kTrapezoidal: return "trapezoidal";
  }
  return "unknown";
}

constexpr std::optional<Integrator> integrator_from_name(std::string_view name) {
  if (name == "explicit_euler") return Integrator::kExplicitEuler;
  if (name == "semi_implicit_euler") return Integrator::kSemiImplicitEuler;
  if (name == "rk4") return Integrator::kRk4;
  if (name == "implicit_euler") return Integrator::kImplicitEuler;
  if (name == "trapezoidal") return Integrator::kTrapezoidal;
  return std::nullopt;
}

/// Right-hand-side evaluations one step of `method` costs (the implicit ones: per Newton
/// iteration, N + 1 for the finite-difference Jacobian and the residual).
constexpr int evaluations_per_step(Integrator method) {
  return method == Integrator::kRk4 ? 4 : 1;
}

template <std::size_t N>
using StateVector = std::array<double, N>;

namespace detail {
template <std::size_t N>
constexpr StateVector<N> axpy(const StateVector<N>& x, double a, const StateVector<N>& d) {
  StateVector<N> out{};
  for (std::size_t i = 0; i < N; ++i) out[i] = x[i] + a * d[i];
  return out;
}
}  // namespace detail

/// x += h f(x).
template <std::size_t N, typename Rhs>
constexpr void explicit_euler_step(StateVector<N>& x, double h, Rhs& rhs) {
  const StateVector<N> d = rhs(x);
  for (std::size_t i = 0; i < N; ++i) x[i] += h * d[i];
}

/// Velocities (and first-order states) first, then positions with the new velocities.
template <std::size_t kPositions, std::size_t N, typename Rhs>
constexpr void semi_implicit_euler_step(StateVector<N>& x, double h, Rhs& rhs) {
  static_assert(2 * kPositions <= N, "the state holds positions, then their velocities");
  const StateVector<N> d = rhs(x);
  for (std::size_t i = kPositions; i < N; ++i) x[i] += h * d[i];
  for (std::size_t i = 0; i < kPositions; ++i) x[i] += h * x[kPositions + i];
}

/// Classical fourth-order Runge–Kutta.
template <std::size_t N, typename Rhs>
constexpr void rk4_step(StateVector<N>& x, double h, Rhs& rhs) {
  const StateVector<N> k1 = rhs(x);
  const StateVector<N> k2 = rhs(detail::axpy(x, 0.5 * h, k1));
  const StateVector<N> k3 = rhs(detail::axpy(x, 0.5 * h, k2));
  const StateVector<N> k4 = rhs(detail::axpy(x, h, k3));
  const double w = h / 6.0;
  for (std::size_t i = 0; i < N; ++i) x[i] += w * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
}

/// The implicit one-step methods: solve x₁ = x₀ + h (θ f(x₁) + (1 − θ) f(x₀)) by Newton's
/// method with a forward-difference Jacobian and Gaussian elimination with partial pivoting
/// (θ = 1: implicit Euler, θ = 1/2: trapezoidal). At most 8 iterations, stopping when the update
/// is below 1e-12 of the state's size; a singular Newton matrix keeps the last iterate. Fixed-size
/// arrays only.
template <std::size_t N, typename Rhs>
constexpr void theta_step(StateVector<N>& x, double h, double theta, Rhs& rhs) {
  const StateVector<N> f0 = rhs(x);
  StateVector<N> base = x;  // x₀ + h (1 − θ) f(x₀)
  for (std::size_t i = 0; i < N; ++i) base[i] += h * (1.0 - theta) * f0[i];
  StateVector<N> y = detail::axpy(x, h, f0);  // explicit Euler as the first guess
  for (int iteration = 0; iteration < 8; ++iteration) {
    const StateVector<N> fy = rhs(y);
    StateVector<N> residual{};  // g(y) = y − base − h θ f(y)
    for (std::size_t i = 0; i < N; ++i) residual[i] = y[i] - base[i] - h * theta * fy[i];
    std::array<std::array<double, N + 1>, N> a{};  // [I − h θ ∂f/∂y | −g]
    for (std::size_t j = 0; j < N; ++j) {
      const double step = 1e-7 * (std::abs(y[j]) + 1e-3);
      StateVector<N> shifted = y;
      shifted[j] += step;
      const StateVector<N> fs = rhs(shifted);
      for (std::size_t i = 0; i < N; ++i) {
        a[i][j] = (i == j ? 1.0 : 0.0) - h * theta * (fs[i] - fy[i]) / step;
      }
    }
    for (std::size_t i = 0; i < N; ++i) a[i][N] = -residual[i];
    for (std::size_t col = 0; col < N; ++col) {  // elimination with partial pivoting
      std::size_t pivot = col;
      for (std::size_t r = col + 1; r < N; ++r) {
        if (std::abs(a[r][col]) > std::abs(a[pivot][col])) pivot = r;
      }
      if (a[pivot][col] == 0.0) {
        x = y;
        return;
      }
      std::swap(a[col], a[pivot]);
      for (std::size_t r = col + 1; r < N; ++r) {
        const double factor = a[r][col] / a[col][col];
        for (std::size_t c = col; c <= N; ++c) a[r][c] -= factor * a[col][c];
      }
    }
    StateVector<N> delta{};
    double size = 0.0, change = 0.0;
    for (std::size_t i = N; i-- > 0;) {
      double sum = a[i][N];
      for (std::size_t c = i + 1; c < N; ++c) sum -= a[i][c] * delta[c];
      delta[i] = sum / a[i][i];
    }
    for (std::size_t i = 0; i < N; ++i) {
      y[i] += delta[i];
      size = std::max(size, std::abs(y[i]));
      change = std::max(change, std::abs(delta[i]));
    }
    if (change <= 1e-12 * (size + 1e-12)) break;
  }
  x = y;
}

/// One step of length h. `kPositions` matters only to the semi-implicit method.
template <std::size_t kPositions, std::size_t N, typename Rhs>
constexpr void integrate_step(Integrator method, StateVector<N>& x, double h, Rhs&& rhs) {
  switch (method) {
    case Integrator::kExplicitEuler: explicit_euler_step(x, h, rhs); return;
    case Integrator::kSemiImplicitEuler: semi_implicit_euler_step<kPositions>(x, h, rhs); return;
    case Integrator::kRk4: rk4_step(x, h, rhs); return;
    case Integrator::kImplicitEuler: theta_step(x, h, 1.0, rhs); return;
    case Integrator::kTrapezoidal: theta_step(x, h, 0.5, rhs); return;
  }
}

/// One tick of length dt as `settings.substeps` (at least one) equal steps. The method is chosen
/// once per tick, outside the sub-step loop, so each loop inlines one method's arithmetic.
template <std::size_t kPositions, std::size_t N, typename Rhs>
constexpr void integrate_tick(const IntegrationSettings& settings, StateVector<N>& x, double dt,
                              Rhs&& rhs) {
  const std::uint32_t n = settings.substeps > 0 ? settings.substeps : 1;
  const double h = dt / static_cast<double>(n);
  switch (settings.method) {
    case Integrator::kExplicitEuler:
      for (std::uint32_t k = 0; k < n; ++k) explicit_euler_step(x, h, rhs);
      return;
    case Integrator::kSemiImplicitEuler:
      for (std::uint32_t k = 0; k < n; ++k) semi_implicit_euler_step<kPositions>(x, h, rhs);
      return;
    case Integrator::kRk4:
      for (std::uint32_t k = 0; k < n; ++k) rk4_step(x, h, rhs);
      return;
    case Integrator::kImplicitEuler:
      for (std::uint32_t k = 0; k < n; ++k) theta_step(x, h, 1.0, rhs);
      return;
    case Integrator::kTrapezoidal:
      for (std::uint32_t k = 0; k < n; ++k) theta_step(x, h, 0.5, rhs);
      return;
  }
}

}  // namespace haptic::engine
