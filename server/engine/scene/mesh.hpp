#pragma once
// Triangle meshes for haptic rendering: the description a client sends (Mesh), its validation,
// and the static bounding-volume hierarchy (MeshBvh) the loop queries. Geometry is in the mesh's
// own object frame O; unit m. Frames per docs/architecture.md.
//
// What a valid mesh is (validate_mesh):
//   - at least one triangle, at most `max_triangles` (and at most 2^31 - 1); at most three
//     vertices per allowed triangle;
//   - every vertex finite, every coordinate within +-kMaxMeshCoordinate (so rounding, about
//     2e-16 * |x|, stays far below the proxy's collision margin);
//   - every index below the vertex count;
//   - no degenerate triangle: twice its area must exceed kMinTriangleShape * (longest edge)^2
//     (a repeated vertex, coincident or collinear vertices all fail);
//   - no triangle repeated (the same three vertex indices in any order);
//   - every edge (a pair of vertex indices) is used by at most two triangles (manifold), and two
//     triangles sharing an edge traverse it in opposite directions (consistent winding).
// Closed meshes are NOT required: an open sheet (a single plate, a terrain) is valid, and the
// god-object proxy treats every triangle as two-sided. Vertices used by no triangle are allowed,
// and so are vertices where two sheets touch at a single point. The winding (counter-clockwise
// seen from outside) only orients the reported normals; contact does not depend on it.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/core/vec3.hpp"

namespace haptic::engine {

/// A triangle mesh in its object frame O.
struct Mesh {
  std::vector<Vec3> vertices_O;                        // Unit: m, frame O.
  std::vector<std::array<std::uint32_t, 3>> triangles;  // Indices into vertices_O.
};

/// Largest accepted |coordinate| of a vertex. Unit: m.
inline constexpr double kMaxMeshCoordinate = 1000.0;
/// A triangle is degenerate when 2 * area <= kMinTriangleShape * (longest edge)^2, i.e. its
/// smallest angle is below about 1e-10 rad. Dimensionless.
inline constexpr double kMinTriangleShape = 1e-10;

/// Returns "" when `mesh` is valid under the rules above, otherwise one message naming the first
/// bad element and its values, e.g. "triangles[17]: zero area (vertices 3, 4, 9)". Allocates;
/// never throws.
std::string validate_mesh(const Mesh& mesh, std::size_t max_triangles);

/// Axis-aligned box in O. Unit: m.
struct Aabb {
  Vec3 min;
  Vec3 max;
};

/// Closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection, 2005,
/// sec. 5.1.5, ClosestPtPointTriangle). All in one frame; unit m.
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

/// Two-sided intersection of the segment p0 -> p1 with triangle (a, b, c). The plane crossing
/// is found from the signed distances d0, d1 of the end points to the triangle's plane: the
/// segment crosses when d0 and d1 are not both > 0, not both < 0 and not both 0 (a segment lying
/// in the plane does not hit); t = d0 / (d0 - d1). The crossing point must lie inside the
/// triangle with barycentric coordinates >= -kBarycentricTolerance, which closes the seams
/// between neighbours. On a hit returns true and sets t in [0, 1].
bool segment_hits_triangle(const Vec3& p0, const Vec3& p1, const Vec3& a, const Vec3& b,
                           const Vec3& c, double& t);
inline constexpr double kBarycentricTolerance = 1e-9;

/// Result of MeshBvh::closest_point.
struct ClosestPointResult {
  bool found = false;
  std::uint32_t triangle = 0;  // Index into Mesh::triangles.
  Vec3 point_O;                // Closest point on the mesh. Unit: m, frame O.
  Vec3 normal_O;               // Unit normal of that triangle from its winding, frame O.
  double distance = 0.0;       // |point_O - query|. Unit: m.
};

/// Result of MeshBvh::first_hit.
struct SegmentHitResult {
  bool hit = false;
  std::uint32_t triangle = 0;  // Index into Mesh::triangles.
  double t = 0.0;              // Crossing at p0 + t (p1 - p0), t in [0, 1].
  Vec3 point_O;                // The crossing point. Unit: m, frame O.
  Vec3 normal_O;               // Unit normal of the triangle from its winding, frame O.
  double plane_offset = 0.0;   // dot(normal_O, x) = plane_offset on the triangle's plane. Unit: m.
};

/// Static bounding-volume hierarchy over a validated mesh (built off the loop, immutable after).
/// Flat arrays: nodes in depth-first order, each with its box and either two children (the left
/// at index + 1, the right at `right`) or a range of at most kLeafSize triangles; triangles stored
/// in leaf order with their precomputed planes. Splits at the median centroid along the longest
/// centroid extent, so the depth is at most ceil(log2(n / kLeafSize)) + 1 <= 31 for any n < 2^32,
/// and the queries' fixed stack of kStackSize = 64 node indices cannot overflow. Queries neither
/// allocate nor throw and are safe to call from several threads at once.
class MeshBvh {
 public:
  static constexpr std::uint32_t kLeafSize = 4;
  static constexpr std::size_t kStackSize = 64;

  MeshBvh() = default;  // An empty hierarchy: no query finds anything.

  /// Builds the hierarchy. Precondition: validate_mesh(mesh, ...) returned "". Allocates.
  static MeshBvh build(const Mesh& mesh);

  /// The triangle closest to p_O among those within `radius` of it (distance <= radius), with its
  /// closest point; found = false when none is. Ties go to the first found.
  ClosestPointResult closest_point(const Vec3& p_O, double radius) const;

  /// The first crossing (smallest t) of the segment p0_O -> p1_O with any triangle, two-sided
  /// (see segment_hits_triangle); hit = false when the segment crosses nothing.
  SegmentHitResult first_hit(const Vec3& p0_O, const Vec3& p1_O) const;

  std::size_t triangle_count() const { return triangles_.size(); }
  std::size_t node_count() const { return nodes_.size(); }
  /// Heap memory the hierarchy holds. Unit: bytes.
  std::size_t memory_bytes() const {
    return nodes_.capacity() * sizeof(Node) + triangles_.capacity() * sizeof(Tri);
  }
  /// Deepest leaf's depth (the root is at depth 1).
  std::uint32_t depth() const { return depth_; }
  /// Box around the whole mesh (padded by kBoxPadding). Unit: m, frame O.
  Aabb bounds() const { return nodes_.empty() ? Aabb{} : nodes_.front().box; }

  /// Boxes are grown by this much on every side so the barycentric tolerance of the triangle
  /// tests is never cut off by a box. Unit: m.
  static constexpr double kBoxPadding = 1e-8;

 private:
  struct Node {
    Aabb box;
    std::uint32_t first = 0;  // Leaf: first triangle; inner: unused.
    std::uint32_t count = 0;  // Leaf: number of triangles (> 0); inner: 0.
    std::uint32_t right = 0;  // Inner: right child (the left child is this node + 1).
  };
  struct Tri {
    Vec3 a, b, c;          // Vertices. Unit: m, frame O.
    Vec3 normal;           // Unit normal from the winding.
    double offset = 0.0;   // dot(normal, a). Unit: m.
    std::uint32_t source = 0;  // Index into Mesh::triangles.
  };

  std::uint32_t build_node(std::vector<std::uint32_t>& order, const std::vector<Vec3>& centroids,
                           const std::vector<Aabb>& boxes, std::uint32_t begin, std::uint32_t end,
                           std::uint32_t depth);

  std::vector<Node> nodes_;
  std::vector<Tri> triangles_;
  std::uint32_t depth_ = 0;
};

}  // namespace haptic::engine
