#pragma once
// haptic-lab's `transparency`: Eom et al.'s design (001) for a device model — the transparency
// index J(B_c) (eq. 11) and the robust-stability norm ‖L‖∞(B_c) (eq. 17) over a log sweep of the
// controller damping B_c, the optimum, and the robust-stability verdict.

#include <ostream>
#include <vector>

#include "engine/analysis/wall_design.hpp"

namespace haptic::lab {

struct TransparencyPoint {
  double controller_damping;  // B_c. Unit: N·s/m.
  double transparency_index;  // J (eq. 11).
  double robust_norm;         // ‖L‖∞ (eq. 17), linear; robustly stable iff ≤ 1.
};

struct TransparencyReport {
  std::vector<TransparencyPoint> sweep;
  engine::OptimalWallDesign optimum;
};

/// Sweeps B_c over [lo, hi] at `points` log-spaced values and finds the optimum. Throws
/// std::invalid_argument naming a bad parameter.
TransparencyReport transparency_study(const engine::WallDesignParams& params, double lo = 0.1,
                                      double hi = 100.0, int points = 41);

/// The sweep as CSV: controller_damping_n_s_m, transparency_index, robust_norm, robust_norm_db.
void write_csv(const TransparencyReport& report, std::ostream& out);

/// A markdown summary: the parameters, the optimum and the verdict, and the sweep as a table.
void write_markdown(const engine::WallDesignParams& params, const TransparencyReport& report,
                    std::ostream& out);

}  // namespace haptic::lab
