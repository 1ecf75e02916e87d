#include "engine/scene/sphere_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace haptic::engine {
namespace {

constexpr std::uint32_t kMaxCellsPerSide = 256;

/// The cell index along one axis of coordinate x (clamped into [0, n)).
std::uint32_t cell_of(double x, double origin, double cell, std::uint32_t n) {
  const double i = std::floor((x - origin) / cell);
  if (!(i > 0.0)) return 0;  // also NaN
  return std::min(static_cast<std::uint32_t>(std::min(i, 1e9)), n - 1);
}

}  // namespace

SphereGrid::SphereGrid(std::span<const Vec3> centers, std::span<const double> radii) {
  const std::size_t n = centers.size();
  if (n == 0) return;
  Vec3 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
          std::numeric_limits<double>::infinity()};
  Vec3 hi = -1.0 * lo;
  double radius_sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3& c = centers[i];
    const double r = radii[i];
    lo = {std::min(lo.x, c.x - r), std::min(lo.y, c.y - r), std::min(lo.z, c.z - r)};
    hi = {std::max(hi.x, c.x + r), std::max(hi.y, c.y + r), std::max(hi.z, c.z + r)};
    radius_sum += r;
  }
  const Vec3 extent = hi - lo;
  const double largest = std::max({extent.x, extent.y, extent.z});
  // About one sphere a cell where they are spread evenly; no smaller than a mean radius (a cell
  // smaller than the spheres lists each in many cells), nor so small the grid passes 256 a side.
  const double volume = std::max(extent.x, 1e-9) * std::max(extent.y, 1e-9) * std::max(extent.z, 1e-9);
  double cell = std::max({std::cbrt(volume / static_cast<double>(n)), radius_sum / static_cast<double>(n),
                          largest / kMaxCellsPerSide, 1e-9});
  for (;;) {
    const auto side = [&](double e) {
      return std::clamp(static_cast<std::uint32_t>(std::ceil(e / cell)), 1u, kMaxCellsPerSide);
    };
    nx_ = side(extent.x);
    ny_ = side(extent.y);
    nz_ = side(extent.z);
    // Count each cell's entries first (CSR), and give up on cells this small if a few large
    // spheres would be listed in too many of them.
    std::size_t total = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3& c = centers[i];
      const double r = radii[i];
      const auto span = [&](double x, double o, std::uint32_t m) {
        return static_cast<std::size_t>(cell_of(x + r, o, cell, m) - cell_of(x - r, o, cell, m) + 1);
      };
      total += span(c.x, lo.x, nx_) * span(c.y, lo.y, ny_) * span(c.z, lo.z, nz_);
    }
    if (total <= 32 * n + 1024) break;
    cell *= 2.0;
  }
  origin_ = lo;
  cell_ = cell;
  const std::size_t cells = static_cast<std::size_t>(nx_) * ny_ * nz_;
  cell_start_.assign(cells + 1, 0);
  const auto for_each_cell = [&](std::size_t i, auto&& visit) {
    const Vec3& c = centers[i];
    const double r = radii[i];
    const std::uint32_t x0 = cell_of(c.x - r, lo.x, cell, nx_), x1 = cell_of(c.x + r, lo.x, cell, nx_);
    const std::uint32_t y0 = cell_of(c.y - r, lo.y, cell, ny_), y1 = cell_of(c.y + r, lo.y, cell, ny_);
    const std::uint32_t z0 = cell_of(c.z - r, lo.z, cell, nz_), z1 = cell_of(c.z + r, lo.z, cell, nz_);
    for (std::uint32_t z = z0; z <= z1; ++z) {
      for (std::uint32_t y = y0; y <= y1; ++y) {
        for (std::uint32_t x = x0; x <= x1; ++x) visit((static_cast<std::size_t>(z) * ny_ + y) * nx_ + x);
      }
    }
  };
  for (std::size_t i = 0; i < n; ++i) for_each_cell(i, [&](std::size_t c) { ++cell_start_[c + 1]; });
  for (std::size_t c = 0; c < cells; ++c) cell_start_[c + 1] += cell_start_[c];
  items_.assign(cell_start_[cells], 0);
  std::vector<std::uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  // Spheres in ascending order, so each cell's list is ascending too.
  for (std::size_t i = 0; i < n; ++i) {
    for_each_cell(i, [&](std::size_t c) { items_[fill[c]++] = static_cast<std::uint32_t>(i); });
  }
}

std::span<const std::uint32_t> SphereGrid::candidates(const Vec3& p_W) const {
  if (cell_start_.empty()) return {};
  // The same arithmetic as the build's cell_of, so a point and the boxes that hold it agree.
  const double x = (p_W.x - origin_.x) / cell_;
  const double y = (p_W.y - origin_.y) / cell_;
  const double z = (p_W.z - origin_.z) / cell_;
  // Outside the grid no sphere's bounding box reaches the point (and NaN is never inside); a point
  // on a far face belongs to the last cell.
  if (!(x >= 0.0 && y >= 0.0 && z >= 0.0 && x <= nx_ && y <= ny_ && z <= nz_)) return {};
  const auto index = [](double v, std::uint32_t n) {
    return std::min(static_cast<std::uint32_t>(std::floor(v)), n - 1);
  };
  const std::size_t c =
      (static_cast<std::size_t>(index(z, nz_)) * ny_ + index(y, ny_)) * nx_ + index(x, nx_);
  return {items_.data() + cell_start_[c], items_.data() + cell_start_[c + 1]};
}

}  // namespace haptic::engine
