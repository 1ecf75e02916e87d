#pragma once
// haptic-lab's `transparency`: Eom et al.'s design (001) for a device model — the transparency
// index J(B_c) (eq. 11) and the robust-stability norm ‖L‖∞(B_c) (eq. 17) over a log sweep of the
// controller damping B_c, the optimum, and the robust-stability verdict — under the chosen hold
// model and, side by side, under each of the others (engine::HoldModel), since near the optimum
// the verdict depends on how the hold is modelled.

#include <optional>
#include <ostream>
#include <vector>

#include "engine/analysis/wall_design.hpp"

namespace haptic::lab {

struct TransparencyPoint {
  double controller_damping;  // B_c. Unit: N·s/m.
  double transparency_index;  // J (eq. 11).
  double robust_norm;         // ‖L‖∞ (eq. 17), linear.
  bool nominal_stable;        // the nominal closed loop is stable
  /// Eom et al.'s Theorem 1: robustly stable iff the nominal loop is stable and ‖L‖∞ < 1; a small
  /// ‖L‖∞ says nothing of a loop that is unstable to begin with.
  bool robust() const { return nominal_stable && robust_norm < 1.0; }
};

/// ‖L‖∞ and the nominal loop's stability of one B_c under one hold model.
struct HoldPoint {
  double robust_norm = 0.0;  // ‖L‖∞ (eq. 17), linear.
  bool nominal_stable = false;
  bool robust() const { return nominal_stable && robust_norm < 1.0; }
};

/// One hold model's view of the design.
struct HoldVerdict {
  engine::HoldModel hold;
  engine::OptimalWallDesign own_optimum;  // the J-optimal B_c under this hold model
  HoldPoint at_report_optimum;            // the report's optimum B_c judged under this hold model
};

struct TransparencyReport {
  std::vector<TransparencyPoint> sweep;
  engine::OptimalWallDesign optimum;
  double swept_to = 0.0;        // The sweep's upper end after any widening. Unit: N·s/m.
  bool optimum_at_edge = false; // The optimum is still at that end (J falls beyond it).
  /// Where the J-optimal B_c is not robustly stable: the sweep point with the smallest J among
  /// those that are (eq. 17), the design Eom et al.'s recursive method settles on, to the grid's
  /// resolution. Empty when the optimum is robust or no swept point is.
  std::optional<TransparencyPoint> best_robust;
  /// Every hold model (engine::kHoldModels order), the chosen one included.
  std::vector<HoldVerdict> holds;
  /// sweep_by_hold[i][j]: sweep point j under holds[i]'s model.
  std::vector<std::vector<HoldPoint>> sweep_by_hold;
};

/// Sweeps B_c over [lo, hi] at `points` log-spaced values per decade-and-a-bit (41 over the
/// default three decades) and finds the optimum. A heavily damped device (000's motor, 003's
/// five-bar) has its optimum above 100 N·s/m: while the optimum lands on the sweep's upper end,
/// the upper end is raised tenfold, up to `widen_limit`. Throws std::invalid_argument naming a
/// bad parameter.
TransparencyReport transparency_study(const engine::WallDesignParams& params, double lo = 0.1,
                                      double hi = 100.0, int points = 41, double widen_limit = 1e5);

/// The sweep as CSV: controller_damping_n_s_m, transparency_index, robust_norm, robust_norm_db,
/// nominal_stable, robust (under the chosen hold model), then robust_norm_db_<hold> and
/// robust_<hold> for every hold model (engine::hold_model_name, '-' written '_').
void write_csv(const TransparencyReport& report, std::ostream& out);

/// A markdown summary: the parameters, the optimum and the verdict, each hold model's verdict, and
/// the sweep as a table.
void write_markdown(const engine::WallDesignParams& params, const TransparencyReport& report,
                    std::ostream& out);

}  // namespace haptic::lab
