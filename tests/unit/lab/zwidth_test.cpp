// haptic-lab zwidth: Colgate's bound, the sampled loop's eigenvalues and simulation on one grid.
#include <gtest/gtest.h>

#include <cmath>

#include <sstream>
#include <stdexcept>

#include "lab/zwidth.hpp"

namespace haptic::lab {
namespace {

ZWidthParams small_grid() {
  ZWidthParams p;  // Eom et al.'s device at 1 kHz
  p.k_points = 10;
  p.b_points = 6;
  p.seconds = 2.0;
  return p;
}

TEST(LabZWidth, TheBoundLiesInsideTheEigenvalueRegionAndSimulationAgreesWithIt_Eq2_6) {
  const ZWidthReport report = zwidth(small_grid());
  ASSERT_EQ(report.cells.size(), 60u);
  EXPECT_TRUE(report.theory_applies);
  std::size_t agree = 0, stable = 0, unstable = 0, passive = 0;
  const ZWidthParams p = small_grid();
  for (const ZWidthCell& c : report.cells) {
    // Colgate's bound (Colgate & Schenkel), b > K T / 2 + |B|, from the cell's own numbers.
    EXPECT_EQ(c.passive, p.damping > c.stiffness * p.period / 2.0 + std::abs(c.damping))
        << c.stiffness << ", " << c.damping;
    if (c.passive) {
      ++passive;
      EXPECT_TRUE(c.eigen_stable) << c.stiffness << ", " << c.damping;  // sufficient
    }
    agree += c.eigen_stable == c.simulation_stable;
    (c.eigen_stable ? stable : unstable) += 1;
  }
  EXPECT_GT(passive, 0u);  // the bound's region is on the grid: the sufficiency check is not empty
  EXPECT_GT(stable, passive);  // and it is strictly inside the stable region here
  EXPECT_GT(stable, 0u);  // the grid crosses the boundary
  EXPECT_GT(unstable, 0u);
  EXPECT_GE(agree, report.cells.size() - 2);  // at most a marginal cell or two on the boundary
  std::ostringstream csv, markdown;
  write_csv(report, csv);
  write_markdown(small_grid(), report, markdown);
  EXPECT_EQ(csv.str().rfind("stiffness_n_m,damping_n_s_m,passive,eigen_stable,simulation_stable\n", 0), 0u);
  EXPECT_NE(markdown.str().find("Passive by Colgate's bound but unstable by eigenvalues: 0"), std::string::npos);
}

TEST(LabZWidth, ADelayShrinksTheRegionAndTheReportSaysTheTheoryDoesNotModelIt) {
  ZWidthParams p = small_grid();
  std::size_t stable_without = 0;
  for (const ZWidthCell& c : zwidth(p).cells) stable_without += c.simulation_stable;
  p.delay_ticks = 2;
  const ZWidthReport delayed = zwidth(p);
  std::size_t stable_with = 0;
  for (const ZWidthCell& c : delayed.cells) stable_with += c.simulation_stable;
  EXPECT_FALSE(delayed.theory_applies);
  EXPECT_LT(stable_with, stable_without);
}

TEST(LabZWidth, BadParametersAreRefusedNamingThem) {
  ZWidthParams p = small_grid();
  p.period = 0.0;
  try {
    zwidth(p);
    FAIL() << "a zero period was accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_EQ(std::string(error.what()).rfind("period:", 0), 0u);
  }
}

}  // namespace
}  // namespace haptic::lab
