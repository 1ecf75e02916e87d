#pragma once
// Golden-section search: the interval about the minimum of a unimodal function, narrowed by the
// golden ratio with one new evaluation a step (Kiefer 1953). Shared by the identification's
// delay and lag searches (engine/analysis/identification_fit.hpp) and 001's wall design
// (engine/analysis/wall_design.cpp).

#include <cmath>
#include <utility>

namespace haptic::engine {

/// [lo, hi] narrowed about the minimum of `f` (unimodal on it; f(x) a double) until hi − lo <=
/// `tolerance` or after `max_steps` steps, whichever comes first. Each step keeps the part that
/// holds the smaller of the two inner points and shrinks it by 0.618….
template <typename F>
std::pair<double, double> golden_section_narrow(F&& f, double lo, double hi, double tolerance, int max_steps) {
  const double r = (std::sqrt(5.0) - 1.0) / 2.0;  // 0.618…
  double x1 = hi - r * (hi - lo);
  double x2 = lo + r * (hi - lo);
  double f1 = f(x1);
  double f2 = f(x2);
  for (int step = 0; step < max_steps && hi - lo > tolerance; ++step) {
    if (f1 < f2) {
      hi = x2;
      x2 = x1;
      f2 = f1;
      x1 = hi - r * (hi - lo);
      f1 = f(x1);
    } else {
      lo = x1;
      x1 = x2;
      f1 = f2;
      x2 = lo + r * (hi - lo);
      f2 = f(x2);
    }
  }
  return {lo, hi};
}

}  // namespace haptic::engine
