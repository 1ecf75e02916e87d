// Routh's array counting right-half-plane roots, on polynomials built from known roots.
#include <gtest/gtest.h>

#include <complex>
#include <vector>

#include "engine/analysis/routh.hpp"

namespace haptic::engine {
namespace {

/// The monic polynomial with these roots (complex ones with their conjugates), highest power first.
std::vector<double> from_roots(const std::vector<std::complex<double>>& roots) {
  std::vector<std::complex<double>> c{1.0};
  for (const auto& r : roots) {
    std::vector<std::complex<double>> next(c.size() + 1, 0.0);
    for (std::size_t i = 0; i < c.size(); ++i) {
      next[i] += c[i];
      next[i + 1] -= r * c[i];
    }
    c = next;
  }
  std::vector<double> real;
  for (const auto& x : c) real.push_back(x.real());
  return real;
}

TEST(Routh, CountsTheRightHalfPlaneRootsOfPolynomialsWithKnownRoots) {
  using C = std::complex<double>;
  struct Case {
    std::vector<C> roots;
    int right;
  };
  const Case cases[] = {
      {{-1.0, -2.0, -3.0}, 0},
      {{1.0, -2.0}, 1},
      {{1.0, 2.0, -3.0}, 2},
      {{C(1, 2), C(1, -2)}, 2},
      {{C(-0.1, 40), C(-0.1, -40), C(-5, 1), C(-5, -1), -300.0}, 0},
      {{C(0.01, 1200), C(0.01, -1200), C(-3, 41), C(-3, -41)}, 2},
      {{C(2, 3), C(2, -3), 4.0, -1.0, -7.0}, 3},
  };
  for (const Case& c : cases) {
    const std::vector<double> p = from_roots(c.roots);
    EXPECT_EQ(routh_right_half_plane_roots(p), c.right) << p.size() - 1;
    EXPECT_EQ(routh_hurwitz_stable(p), c.right == 0);
  }
  // A zero in the first column: s⁴ + s³ + 2s² + 2s + 3 has two roots on the right.
  const double zero_lead[] = {1.0, 1.0, 2.0, 2.0, 3.0};
  EXPECT_EQ(routh_right_half_plane_roots(zero_lead), 2);
  EXPECT_FALSE(routh_hurwitz_stable(zero_lead));
  // A missing coefficient is never Hurwitz (s³ + s, roots on the axis).
  const double on_axis[] = {1.0, 0.0, 1.0, 0.0};
  EXPECT_FALSE(routh_hurwitz_stable(on_axis));
}

}  // namespace
}  // namespace haptic::engine
