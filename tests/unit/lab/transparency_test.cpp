// haptic-lab transparency: 001's controller design swept over B_c (Eom et al., eqs. 11 and 17).
#include <gtest/gtest.h>

#include <algorithm>
#include <sstream>
#include <stdexcept>

#include "lab/transparency.hpp"

namespace haptic::lab {
namespace {

TEST(LabTransparency, TheSweepHasAnInteriorMinimumAtTheOptimumWhichIsRobust_Eq11_Eq17) {
  const engine::WallDesignParams params;  // Eom et al.'s experiment
  const TransparencyReport report = transparency_study(params);
  ASSERT_EQ(report.sweep.size(), 41u);
  EXPECT_NEAR(report.optimum.controller_damping, 15.0, 0.5);  // 001 Fig. 8: 15 N·s/m
  EXPECT_TRUE(report.optimum.robustly_stable);
  EXPECT_FALSE(report.best_robust.has_value());  // the optimum itself is robust
  const auto best = std::min_element(report.sweep.begin(), report.sweep.end(),
                                     [](const TransparencyPoint& a, const TransparencyPoint& b) {
                                       return a.transparency_index < b.transparency_index;
                                     });
  EXPECT_GT(best - report.sweep.begin(), 0);  // interior, not at an end of the sweep
  EXPECT_LT(best - report.sweep.begin(), 40);
  EXPECT_GE(best->transparency_index, report.optimum.transparency_index);  // the search refines it
  // Light damping is not robust (eq. 17, Fig. 8): the sweep's points around B_c = 1 say so.
  for (const TransparencyPoint& point : report.sweep) {
    if (point.controller_damping > 0.5 && point.controller_damping < 2.0) {
      EXPECT_GT(point.robust_norm, 1.0) << point.controller_damping;
    }
  }
  std::ostringstream csv, markdown;
  write_csv(report, csv);
  write_markdown(params, report, markdown);
  EXPECT_EQ(csv.str().rfind("controller_damping_n_s_m,transparency_index,robust_norm,robust_norm_db,"
                            "nominal_stable,robust,robust_norm_db_second_order,robust_second_order,"
                            "robust_norm_db_delay,robust_delay,robust_norm_db_pade,robust_pade,"
                            "robust_norm_db_exact,robust_exact\n", 0),
            0u);
  EXPECT_NE(markdown.str().find("robustly stable"), std::string::npos);
}

TEST(LabTransparency, AHeavilyDampedDeviceWidensTheSweepUntilTheOptimumIsInside) {
  engine::WallDesignParams params;  // 000's DC motor as haptic-lab's --device model gives it
  params.mass = 0.1076;
  params.damping = 7.868;
  const TransparencyReport report = transparency_study(params);
  EXPECT_GT(report.swept_to, 100.0);  // the default [0.1, 100] ends below the optimum
  EXPECT_FALSE(report.optimum_at_edge);
  EXPECT_GT(report.optimum.controller_damping, 100.0);
  EXPECT_LT(report.optimum.controller_damping, 0.999 * report.swept_to);
  EXPECT_NEAR(report.sweep.back().controller_damping, report.swept_to, 1e-9 * report.swept_to);
  // There J's optimum is not robustly stable (eq. 17); the best swept B_c that is, is reported.
  ASSERT_FALSE(report.optimum.robustly_stable);
  ASSERT_TRUE(report.best_robust.has_value());
  EXPECT_TRUE(report.best_robust->robust());
  EXPECT_GT(report.best_robust->transparency_index, report.optimum.transparency_index);
  for (const TransparencyPoint& point : report.sweep) {
    if (point.robust()) {
      EXPECT_GE(point.transparency_index, report.best_robust->transparency_index);
    }
  }
  // Narrowing the widening limit leaves it at the edge, and the report says so.
  const TransparencyReport capped = transparency_study(params, 0.1, 100.0, 41, 100.0);
  EXPECT_TRUE(capped.optimum_at_edge);
  std::ostringstream markdown;
  write_markdown(params, capped, markdown);
  EXPECT_NE(markdown.str().find("at the sweep's upper end (100 N·s/m)"), std::string::npos) << markdown.str();
}

TEST(LabTransparency, BadParametersAreRefusedNamingThem) {
  engine::WallDesignParams params;
  params.mass = -1.0;
  try {
    transparency_study(params);
    FAIL() << "a negative mass was accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_EQ(std::string(error.what()).rfind("mass:", 0), 0u);
  }
  EXPECT_THROW(transparency_study(engine::WallDesignParams{}, 10.0, 1.0), std::invalid_argument);
}

// Robust means a stable nominal loop and ‖L‖∞ < 1 (Eom et al., Theorem 1): on the default device
// B_c = 84 and 100 N·s/m have ‖L‖∞ of −3 and −6 dB but an unstable nominal loop, so they are not.
TEST(LabTransparency, AnUnstableNominalLoopIsNeverCalledRobust) {
  const TransparencyReport report = transparency_study(engine::WallDesignParams{});
  std::size_t checked = 0;
  for (const TransparencyPoint& point : report.sweep) {
    EXPECT_EQ(point.robust(), point.nominal_stable && point.robust_norm < 1.0);
    if (point.controller_damping > 80.0 && point.controller_damping <= 100.0) {
      EXPECT_LT(point.robust_norm, 1.0) << point.controller_damping;
      EXPECT_FALSE(point.nominal_stable) << point.controller_damping;
      EXPECT_FALSE(point.robust()) << point.controller_damping;
      ++checked;
    }
  }
  EXPECT_GE(checked, 2u);
  std::ostringstream markdown;
  write_markdown(engine::WallDesignParams{}, report, markdown);
  EXPECT_NE(markdown.str().find("| 100 | 4.46938 | -6.24727 | UNSTABLE | no |"), std::string::npos)
      << markdown.str();
}

// Eom et al. leave the hold's model open; at the optimum the verdict flips with it: robust under
// the second-order approximation (−0.32 dB), the first-order Padé (−0.09 dB) and the exact hold
// (−0.72 dB), not under a pure T/2 delay (+0.99 dB). The report gives every model's verdict, each
// one's own optimum, and the sweep under the model chosen.
TEST(LabTransparency, EveryHoldModelsVerdictIsReportedAndTheyDifferAtTheOptimum) {
  const engine::WallDesignParams params;
  const TransparencyReport report = transparency_study(params);
  ASSERT_EQ(report.holds.size(), 4u);
  ASSERT_EQ(report.sweep_by_hold.size(), 4u);
  const double optimum = report.optimum.controller_damping;
  for (std::size_t i = 0; i < report.holds.size(); ++i) {
    const HoldVerdict& h = report.holds[i];
    EXPECT_EQ(h.hold, engine::kHoldModels[i]);
    engine::WallDesignParams q = params;
    q.hold = h.hold;
    EXPECT_DOUBLE_EQ(h.at_report_optimum.robust_norm, engine::robust_stability_norm(q, optimum));
    EXPECT_TRUE(h.at_report_optimum.nominal_stable);
    EXPECT_NEAR(h.own_optimum.controller_damping, 15.0, 0.6) << engine::hold_model_name(h.hold);
    ASSERT_EQ(report.sweep_by_hold[i].size(), report.sweep.size());
  }
  EXPECT_EQ(report.holds[0].at_report_optimum.robust_norm, report.optimum.robust_stability_norm);
  EXPECT_TRUE(report.holds[0].at_report_optimum.robust());   // second-order
  EXPECT_FALSE(report.holds[1].at_report_optimum.robust());  // e^{−sT/2}
  EXPECT_GT(engine::to_db(report.holds[1].at_report_optimum.robust_norm), 0.9);
  EXPECT_TRUE(report.holds[2].at_report_optimum.robust());   // Padé
  EXPECT_TRUE(report.holds[3].at_report_optimum.robust());   // exact
  // The pure delay's nominal limit π m / T = 31.4 N·s/m sits below the second-order model's 49.3.
  for (std::size_t j = 0; j < report.sweep.size(); ++j) {
    const double B_c = report.sweep[j].controller_damping;
    if (B_c > 33.0 && B_c < 47.0) {
      EXPECT_TRUE(report.sweep_by_hold[0][j].nominal_stable) << B_c;
      EXPECT_FALSE(report.sweep_by_hold[1][j].nominal_stable) << B_c;
    }
  }
  std::ostringstream markdown;
  write_markdown(params, report, markdown);
  EXPECT_NE(markdown.str().find("| delay | e^(−sT/2) |"), std::string::npos) << markdown.str();
  EXPECT_NE(markdown.str().find("| NOT robustly stable |\n"), std::string::npos) << markdown.str();

  // --hold delay: the sweep and optimum are the delay model's.
  engine::WallDesignParams delayed = params;
  delayed.hold = engine::HoldModel::kHalfPeriodDelay;
  const TransparencyReport under_delay = transparency_study(delayed);
  EXPECT_FALSE(under_delay.optimum.robustly_stable);
  EXPECT_NEAR(under_delay.optimum.controller_damping, report.holds[1].own_optimum.controller_damping, 1e-9);
  ASSERT_TRUE(under_delay.best_robust.has_value());  // a heavier B_c is robust under the delay too
  EXPECT_TRUE(under_delay.best_robust->robust());
}

}  // namespace
}  // namespace haptic::lab
