// The stability verdict by growth (engine/analysis/growth): a slow ring-up is unstable however
// small it still is, a decay, an undamped oscillation or a run that decayed into rounding is not.
// Each signal is sampled as the studies sample theirs.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "engine/analysis/growth.hpp"

namespace haptic::engine {
namespace {

/// x_k = pole^k cos(ω k T): a closed-loop pole of magnitude `pole` per sample of period T.
std::vector<double> ringing(double pole, double period_s, double seconds, double omega = 40.0) {
  std::vector<double> x;
  const auto n = static_cast<std::size_t>(std::llround(seconds / period_s));
  for (std::size_t k = 0; k < n; ++k) {
    x.push_back(std::pow(pole, static_cast<double>(k)) * std::cos(omega * static_cast<double>(k) * period_s));
  }
  return x;
}

TEST(Growth, APoleAt1Point001RingsUpWhereASizeCriterionSeesNothing) {
  // The federation study's verdict: 1 kHz, 0.5 s windows from 12.5 s of a 26 s run.
  const std::vector<double> x = ringing(1.001, 1e-3, 26.0);
  const GrowthFit fit = envelope_growth(x, 1e-3, 12.5, 0.5, 1e-9);
  EXPECT_NEAR(fit.rate_per_s, std::log(1.001) / 1e-3, 0.02);
  EXPECT_TRUE(rings_up(fit));
  // The numerics study's: a 0.5 s run, its second half in eighths, sampled every 10 ms, with a
  // pole at 1.001 a millisecond: 1.65× over the run, never 10× the start.
  std::vector<double> coarse;
  const std::vector<double> fine = ringing(1.001, 1e-3, 0.5, 300.0);
  for (std::size_t k = 0; k < fine.size(); k += 10) coarse.push_back(fine[k] * fine[k]);  // an energy
  EXPECT_LT(std::abs(coarse.back()), 10.0 * std::abs(coarse.front()));
  EXPECT_TRUE(rings_up(envelope_growth(coarse, 1e-2, 0.25, 0.5 / 16.0, 1e-9)));
}

TEST(Growth, DecayUndampedOscillationAndRoundingDoNotRingUp) {
  EXPECT_FALSE(rings_up(envelope_growth(ringing(0.999, 1e-3, 26.0), 1e-3, 12.5, 0.5, 1e-9)));
  const GrowthFit undamped = envelope_growth(ringing(1.0, 1e-3, 26.0), 1e-3, 12.5, 0.5, 1e-9);
  EXPECT_NEAR(undamped.rate_per_s, 0.0, 0.01);
  EXPECT_FALSE(rings_up(undamped));
  // Decayed far below the floor, then rounding noise that does not decay: left out, not growth.
  std::vector<double> rounding = ringing(0.95, 1e-3, 26.0);
  for (std::size_t k = 2000; k < rounding.size(); ++k) rounding[k] = 1e-17 * std::cos(1.3 * static_cast<double>(k));
  const GrowthFit rested = envelope_growth(rounding, 1e-3, 12.5, 0.5, 1e-9);
  EXPECT_EQ(rested.windows, 0u);
  EXPECT_FALSE(rings_up(rested));
}

TEST(Growth, ARunGrowingAsItsReferenceDoesDoesNotRingUpAndANonFiniteOneDoes) {
  const GrowthFit reference = envelope_growth(ringing(1.0005, 1e-3, 10.0), 1e-3, 5.0, 0.5, 1e-9);
  const GrowthFit same = envelope_growth(ringing(1.0005, 1e-3, 10.0), 1e-3, 5.0, 0.5, 1e-9);
  EXPECT_TRUE(rings_up(same));              // alone, 0.5/s is growth
  EXPECT_FALSE(rings_up(same, &reference)); // beside a reference that grows as fast, it is not
  std::vector<double> blown = ringing(1.0, 1e-3, 10.0);
  blown[8000] = NAN;
  EXPECT_TRUE(rings_up(envelope_growth(blown, 1e-3, 5.0, 0.5, 1e-9)));
}

}  // namespace
}  // namespace haptic::engine
