#pragma once
// A broad phase for the sphere stage: a uniform grid over the spheres' bounding boxes, built off
// the loop when a scene has enough spheres to need it (CompiledScene compiles it from
// kSphereGridMinSpheres on; a smaller scene pays nothing). A tool point can touch only the spheres
// listed in the cell it is in, so a tick looks at those instead of all of them.

#include <cstdint>
#include <span>
#include <vector>

#include "engine/core/vec3.hpp"

namespace haptic::engine {

/// From this many spheres on, compile_scene builds a SphereGrid (below it, looking at every sphere
/// costs less than the grid's own work: about 7 ns a sphere).
inline constexpr std::size_t kSphereGridMinSpheres = 64;

class SphereGrid {
 public:
  SphereGrid() = default;

  /// Builds the grid over spheres (centres in W, radii; Unit: m). Cells are cubes about the mean
  /// spacing of the spheres (and at least their mean radius), at most 256 a side; a sphere is
  /// listed in every cell its bounding box meets. Allocates; not for the loop.
  SphereGrid(std::span<const Vec3> centers, std::span<const double> radii);

  bool empty() const { return cell_start_.empty(); }

  /// The spheres whose bounding boxes meet the cell holding p_W (indices into the spheres given to
  /// the constructor, ascending); none outside the grid. Does not allocate.
  std::span<const std::uint32_t> candidates(const Vec3& p_W) const;

  /// How many entries the cells hold in all (a sphere once per cell it meets).
  std::size_t entries() const { return items_.size(); }
  /// The cell's edge. Unit: m.
  double cell_size() const { return cell_; }

 private:
  Vec3 origin_;                 // the grid's lowest corner in W. Unit: m.
  double cell_ = 1.0;           // Unit: m.
  std::uint32_t nx_ = 0, ny_ = 0, nz_ = 0;
  std::vector<std::uint32_t> cell_start_;  // CSR: cell c's spheres are items_[start[c], start[c + 1])
  std::vector<std::uint32_t> items_;
};

}  // namespace haptic::engine
