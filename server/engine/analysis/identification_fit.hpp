#pragma once
// What the two fits of a device axis share (engine/analysis/system_identification: at the
// excited harmonics; engine/analysis/moving_stretch_fit: in time, where the axis moves): the
// parameters of one fit, and the one-dimensional search each runs for the delay and the lag.
// Internal to engine/analysis.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>

#include "engine/core/golden_section.hpp"

namespace haptic::engine::identification {

/// One fit of F(t − τ) / (1 + sτ_a) = m ẍ + b ẋ + c sgn(ẋ) + f0 (system_identification.hpp's (1)).
struct Parameters {
  double mass = 0, damping = 0, coulomb = 0, offset = 0, delay = 0, lag = 0;
  double residual = 0;      // the sum of the squared residuals the fit minimised. Unit: N².
  double force_power = 0;   // the sum of the squared forces over the same terms. Unit: N².
};

/// The parameters minimising the residual of `at(v)` over v in [lo_limit, hi_limit]: a grid of
/// `grid` steps (the residual has local minima, for τ a period of the highest harmonic apart),
/// then a golden-section search of `refine` steps between the best point's neighbours.
template <typename At>
Parameters minimise(const At& at, double lo_limit, double hi_limit, std::size_t grid, int refine) {
  const double step = (hi_limit - lo_limit) / static_cast<double>(grid);
  double best_v = lo_limit;
  Parameters best = at(lo_limit);
  for (std::size_t i = 1; i <= grid; ++i) {
    const double v = lo_limit + step * static_cast<double>(i);
    const Parameters p = at(v);
    if (p.residual < best.residual) {
      best = p;
      best_v = v;
    }
  }
  const auto [lo, hi] = golden_section_narrow([&](double v) { return at(v).residual; },
                                               std::max(lo_limit, best_v - step), std::min(hi_limit, best_v + step),
                                               0.0, refine);
  const Parameters middle = at(0.5 * (lo + hi));
  return middle.residual <= best.residual ? middle : best;
}

/// The least-squares solution of the normal equations ata θ = atb, its columns scaled to unit norm
/// first (a mass's column is ω² or t² larger than a damping's). A column the others already span
/// (no reversal seen: the friction's is zero, or the constant's) is left out: its unknown is 0 and
/// `used` says so.
template <std::size_t N>
std::array<double, N> least_squares(const double (&ata)[N][N], const double (&atb)[N], std::array<bool, N>& used) {
  std::array<double, N> scale{};
  for (std::size_t r = 0; r < N; ++r) scale[r] = ata[r][r] > 0.0 ? 1.0 / std::sqrt(ata[r][r]) : 0.0;
  double m[N][N + 1];
  for (std::size_t r = 0; r < N; ++r) {
    for (std::size_t c = 0; c < N; ++c) m[r][c] = ata[r][c] * scale[r] * scale[c];
    m[r][N] = atb[r] * scale[r];
  }
  // Gauss–Jordan with partial pivoting over the rows not yet taken.
  std::array<std::size_t, N> pivot_row{};
  std::array<bool, N> row_taken{};
  used = {};
  for (std::size_t col = 0; col < N; ++col) {
    std::size_t pivot = N;
    for (std::size_t r = 0; r < N; ++r) {
      if (!row_taken[r] && (pivot == N || std::abs(m[r][col]) > std::abs(m[pivot][col]))) pivot = r;
    }
    if (pivot == N || !(std::abs(m[pivot][col]) > 1e-10)) continue;
    used[col] = true;
    row_taken[pivot] = true;
    pivot_row[col] = pivot;
    for (std::size_t r = 0; r < N; ++r) {
      if (r == pivot) continue;
      const double factor = m[r][col] / m[pivot][col];
      for (std::size_t c = col; c <= N; ++c) m[r][c] -= factor * m[pivot][c];
    }
  }
  std::array<double, N> solution{};
  for (std::size_t col = 0; col < N; ++col) {
    solution[col] = used[col] ? m[pivot_row[col]][N] / m[pivot_row[col]][col] * scale[col] : 0.0;
  }
  return solution;
}

}  // namespace haptic::engine::identification
