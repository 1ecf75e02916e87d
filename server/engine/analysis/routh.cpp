#include "engine/analysis/routh.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>

namespace haptic::engine {

int routh_right_half_plane_roots(std::span<const double> a) {
  constexpr std::size_t kMaxCoefficients = 17;
  assert(!a.empty() && a.size() <= kMaxCoefficients && a[0] != 0.0);
  const std::size_t n = a.size();
  const std::size_t width = (n + 1) / 2;
  std::array<std::array<double, kMaxCoefficients>, kMaxCoefficients> row{};
  for (std::size_t i = 0; i < n; ++i) row[i % 2][i / 2] = a[i];
  const auto fix_zero_lead = [&](std::size_t r) {
    if (row[r][0] != 0.0) return;
    double scale = 0.0;
    for (std::size_t i = 0; i < width; ++i) scale = std::max(scale, std::abs(row[r][i]));
    for (std::size_t i = 0; i < width; ++i) scale = std::max(scale, std::abs(row[r - 1][i]));
    row[r][0] = 1e-12 * (scale > 0.0 ? scale : 1.0);
  };
  if (n > 1) fix_zero_lead(1);
  for (std::size_t r = 2; r < n; ++r) {
    for (std::size_t i = 0; i + 1 < width; ++i) {
      row[r][i] = (row[r - 1][0] * row[r - 2][i + 1] - row[r - 2][0] * row[r - 1][i + 1]) / row[r - 1][0];
    }
    fix_zero_lead(r);
  }
  int changes = 0;
  for (std::size_t r = 1; r < n; ++r) {
    if ((row[r][0] > 0.0) != (row[r - 1][0] > 0.0)) ++changes;
  }
  return changes;
}

bool routh_hurwitz_stable(std::span<const double> a) {
  const double sign = a[0] > 0.0 ? 1.0 : -1.0;
  for (const double c : a) {
    if (!(sign * c > 0.0)) return false;
  }
  return routh_right_half_plane_roots(a) == 0;
}

}  // namespace haptic::engine
