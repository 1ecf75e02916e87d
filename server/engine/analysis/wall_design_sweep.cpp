#include "engine/analysis/wall_design_sweep.hpp"

namespace haptic::engine {

std::vector<OptimalWallDesign> optimise_over_weight_cutoffs(const WallDesignParams& p,
                                                            std::span<const double> weight_cutoffs,
                                                            double lo, double hi) {
  std::vector<OptimalWallDesign> out;
  out.reserve(weight_cutoffs.size());
  for (const double cutoff : weight_cutoffs) {
    WallDesignParams q = p;
    q.weight_cutoff = cutoff;
    out.push_back(optimise_controller_damping(q, lo, hi));
  }
  return out;
}

}  // namespace haptic::engine
