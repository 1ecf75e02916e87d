// haptic-lab zwidth: Colgate's bound, the sampled loop's eigenvalues and simulation on one grid.
#include <gtest/gtest.h>

#include <cmath>

#include <sstream>
#include <stdexcept>

#include "engine/scene/impedance.hpp"
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

// With a delay the eigenvalues model it too (z^-d on the wall's force): they and simulation still
// agree, the region shrinks, and Colgate's bound (which assumes no delay) is not applied.
TEST(LabZWidth, ADelayShrinksTheRegionAndTheEigenvaluesModelIt) {
  ZWidthParams p = small_grid();
  std::size_t stable_without = 0;
  for (const ZWidthCell& c : zwidth(p).cells) stable_without += c.eigen_stable;
  for (const std::uint32_t delay : {1u, 2u}) {
    p.delay_ticks = delay;
    const ZWidthReport delayed = zwidth(p);
    std::size_t stable_with = 0, agree = 0;
    for (const ZWidthCell& c : delayed.cells) {
      stable_with += c.eigen_stable;
      agree += c.eigen_stable == c.simulation_stable;
      EXPECT_FALSE(c.passive);
    }
    EXPECT_TRUE(delayed.theory_applies);
    EXPECT_FALSE(delayed.passivity_applies);
    EXPECT_LT(stable_with, stable_without) << delay;
    EXPECT_GE(agree, delayed.cells.size() - 2) << delay;  // a marginal cell or two at most
    std::ostringstream csv, markdown;
    write_csv(delayed, csv);
    write_markdown(p, delayed, markdown);
    EXPECT_NE(csv.str().find(",n/a,"), std::string::npos);
    EXPECT_NE(markdown.str().find("assumes no delay: not applied here"), std::string::npos);
  }
}

// The boundary K'(B) of the delayed loop by the eigenvalues is the one simulation finds: at 0.99 K'
// the simulated wall settles, at 1.01 K' it does not (the undelayed K' would be 3x too high).
TEST(LabZWidth, TheDelayedEigenvalueBoundaryIsTheSimulatedOne) {
  const engine::MassDamperDevice device{0.01, 0.022};
  constexpr double kT = 1e-3;
  for (const double B : {0.0, 0.5}) {
    const double without = engine::sampled_wall_margin({1000.0, B, 0.0},
                                                       engine::ImpedanceDiscretization::kBackwardDifference,
                                                       device, kT)
                               .max_stable_stiffness;
    const double with = engine::sampled_wall_margin({1000.0, B, 0.0},
                                                    engine::ImpedanceDiscretization::kBackwardDifference,
                                                    device, kT, 1)
                            .max_stable_stiffness;
    EXPECT_LT(with, 0.6 * without) << B;
    ZWidthParams p;
    p.delay_ticks = 1;
    p.k_min = 0.99 * with;
    p.k_max = 1.01 * with;
    p.k_points = 2;
    p.b_max = B > 0.0 ? B : 1.0;
    p.b_points = 2;  // B = 0 and b_max
    p.seconds = 3.0;
    const ZWidthReport report = zwidth(p);
    const std::size_t column = B > 0.0 ? 1 : 0;
    EXPECT_TRUE(report.cells[0 * 2 + column].simulation_stable) << "B " << B << " at 0.99 K'";
    EXPECT_FALSE(report.cells[1 * 2 + column].simulation_stable) << "B " << B << " at 1.01 K'";
  }
}

// Each column's boundary: Colgate's K = 2(b − |B|)/T (eq. 2.6 solved for K), the eigenvalues' K',
// and the simulation's, found by bisection, agreeing with the eigenvalues to 0.5 % (a 2 s run cannot
// tell a pole just outside the unit circle from one on it: at B = 10 the simulation's K is 0.12 %
// above the eigenvalues').
TEST(LabZWidth, TheBoundaryAtEachDampingIsPrintedFromEachTest_Eq2_6) {
  for (const std::uint32_t delay : {0u, 1u}) {
    ZWidthParams p = small_grid();
    p.delay_ticks = delay;
    const ZWidthReport report = zwidth(p);
    ASSERT_EQ(report.boundary.size(), static_cast<std::size_t>(p.b_points));
    std::size_t compared = 0;
    for (const ZWidthBoundary& edge : report.boundary) {
      if (delay == 0) {
        EXPECT_DOUBLE_EQ(edge.k_max_colgate, std::max(0.0, 2.0 * (p.damping - edge.damping) / p.period));
        EXPECT_LE(edge.k_max_colgate, edge.k_max_eigen);  // the bound is sufficient
      } else {
        EXPECT_TRUE(std::isnan(edge.k_max_colgate));
      }
      if (std::isfinite(edge.k_max_eigen) && edge.k_max_eigen > 0.0) {
        EXPECT_NEAR(edge.k_max_simulation, edge.k_max_eigen, 5e-3 * edge.k_max_eigen)
            << "delay " << delay << ", B " << edge.damping;
        ++compared;
      }
    }
    EXPECT_GE(compared, static_cast<std::size_t>(p.b_points - 1));
    std::ostringstream markdown;
    write_markdown(p, report, markdown);
    EXPECT_NE(markdown.str().find("| B (N·s/m) | Colgate 2(b − |B|)/T (N/m) | eigenvalues (N/m) | simulation (N/m) |"),
              std::string::npos);
  }
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
