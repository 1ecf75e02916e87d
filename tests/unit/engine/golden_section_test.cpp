// engine::golden_section_narrow (engine/core/golden_section.hpp): the interval it leaves holds
// the minimum, shrinks by the golden ratio a step, and stops at the tolerance or the step count.
#include <gtest/gtest.h>

#include <cmath>

#include "engine/core/golden_section.hpp"

namespace haptic::engine {
namespace {

TEST(GoldenSection, NarrowsToTheToleranceAboutTheMinimum) {
  int evaluations = 0;
  const auto f = [&](double x) {
    ++evaluations;
    return (x - 0.3) * (x - 0.3);
  };
  const auto [lo, hi] = golden_section_narrow(f, -1.0, 2.0, 1e-9, 10000);
  EXPECT_LE(hi - lo, 1e-9);
  EXPECT_LE(lo, 0.3 + 1e-12);
  EXPECT_GE(hi, 0.3 - 1e-12);
  // One evaluation a step after the first two: log(3e9) / log(1 / 0.618) = 45.3 steps.
  EXPECT_EQ(evaluations, 2 + 46);
}

TEST(GoldenSection, StopsAfterItsStepsWithTheIntervalShrunkByTheRatioEach) {
  const auto [lo, hi] = golden_section_narrow([](double x) { return std::abs(x - 0.9); }, 0.0, 1.0, 0.0, 10);
  EXPECT_NEAR(hi - lo, std::pow((std::sqrt(5.0) - 1.0) / 2.0, 10), 1e-12);
  EXPECT_LE(lo, 0.9);
  EXPECT_GE(hi, 0.9);
}

TEST(GoldenSection, AMinimumAtAnEndIsKept) {
  const auto [lo, hi] = golden_section_narrow([](double x) { return x; }, 2.0, 5.0, 1e-6, 10000);
  EXPECT_NEAR(lo, 2.0, 1e-12);
  EXPECT_LE(hi - lo, 1e-6);
}

}  // namespace
}  // namespace haptic::engine
