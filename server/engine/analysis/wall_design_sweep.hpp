#pragma once
// How the transparency optimum of the wall controller's velocity gain B_c moves with the cut-off
// of the weight w1 (Eom, Suh, Yi, eq. 11, Fig. 8), which the document leaves open ("a low pass
// filter"). Off the loop: it allocates its result.

#include <span>
#include <vector>

#include "engine/analysis/wall_design.hpp"

namespace haptic::engine {

/// One optimum per entry of `weight_cutoffs` (ω_1 of w1, Unit: rad/s, each > 0), in that order:
/// optimise_controller_damping(p with weight_cutoff = ω_1, lo, hi), the other parameters from `p`.
/// Unit of lo, hi: N·s/m; 0 < lo < hi.
std::vector<OptimalWallDesign> optimise_over_weight_cutoffs(const WallDesignParams& p,
                                                            std::span<const double> weight_cutoffs,
                                                            double lo = 0.1, double hi = 100.0);

}  // namespace haptic::engine
