// Triangle meshes and the god-object proxy: validation, BVH queries against brute force, thin
// plates, concave edges and vertices, convex facets, moving and replaced meshes, free space, and
// no allocation per tick.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "engine/scene/god_object.hpp"
#include "engine/scene/mesh.hpp"
#include "support/allocation_counter.hpp"

namespace haptic::engine {
namespace {

constexpr double kK = 1000.0;      // N/m
constexpr double kMargin = 1e-6;   // m, the default

GodObjectParams params(double damping = 0.0) {
  GodObjectParams p;
  p.stiffness = kK;
  p.damping = damping;
  return p;
}

/// Builds meshes from quads, merging vertices with equal coordinates so neighbours share edges.
struct MeshBuilder {
  Mesh mesh;
  std::map<std::tuple<double, double, double>, std::uint32_t> index;

  std::uint32_t vertex(const Vec3& p) {
    const auto key = std::make_tuple(p.x, p.y, p.z);
    const auto it = index.find(key);
    if (it != index.end()) return it->second;
    mesh.vertices_O.push_back(p);
    const auto i = static_cast<std::uint32_t>(mesh.vertices_O.size() - 1);
    index.emplace(key, i);
    return i;
  }
  void triangle(const Vec3& a, const Vec3& b, const Vec3& c) {
    mesh.triangles.push_back({vertex(a), vertex(b), vertex(c)});
  }
  /// p0..p3 counter-clockwise seen from the side the normal points to.
  void quad(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3) {
    triangle(p0, p1, p2);
    triangle(p0, p2, p3);
  }
};

/// A square plate of zero thickness at height z, normal +z, half-width h.
Mesh plate(double z = 0.0, double h = 0.1) {
  MeshBuilder b;
  b.quad({-h, -h, z}, {h, -h, z}, {h, h, z}, {-h, h, z});
  return b.mesh;
}

/// Concave edge: floor z = 0 (x in [0, 0.1]) and wall x = 0 (z in [0, 0.1]), y in [-0.1, 0.1];
/// the free side is x > 0, z > 0.
Mesh corner_edge() {
  MeshBuilder b;
  b.quad({0, -0.1, 0}, {0.1, -0.1, 0}, {0.1, 0.1, 0}, {0, 0.1, 0});
  b.quad({0, -0.1, 0}, {0, 0.1, 0}, {0, 0.1, 0.1}, {0, -0.1, 0.1});
  return b.mesh;
}

/// Concave vertex: floor z = 0, walls x = 0 and y = 0, each 0.1 m square; free side x, y, z > 0.
Mesh corner_vertex() {
  MeshBuilder b;
  b.quad({0, 0, 0}, {0.1, 0, 0}, {0.1, 0.1, 0}, {0, 0.1, 0});
  b.quad({0, 0, 0}, {0, 0.1, 0}, {0, 0.1, 0.1}, {0, 0, 0.1});
  b.quad({0, 0, 0}, {0, 0, 0.1}, {0.1, 0, 0.1}, {0.1, 0, 0});
  return b.mesh;
}

/// Closed icosphere (outward winding) of the given radius: 20 * 4^levels triangles.
Mesh icosphere(double radius, int levels) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> v = {{-1, t, 0}, {1, t, 0},  {-1, -t, 0}, {1, -t, 0},
                         {0, -1, t}, {0, 1, t},  {0, -1, -t}, {0, 1, -t},
                         {t, 0, -1}, {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<std::uint32_t, 3>> f = {
      {0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoints;
    auto middle = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      const auto it = midpoints.find(key);
      if (it != midpoints.end()) return it->second;
      v.push_back((v[a] + v[b]) * 0.5);
      const auto i = static_cast<std::uint32_t>(v.size() - 1);
      midpoints.emplace(key, i);
      return i;
    };
    std::vector<std::array<std::uint32_t, 3>> next;
    for (const auto& tri : f) {
      const std::uint32_t a = middle(tri[0], tri[1]);
      const std::uint32_t b = middle(tri[1], tri[2]);
      const std::uint32_t c = middle(tri[2], tri[0]);
      next.push_back({tri[0], a, c});
      next.push_back({tri[1], b, a});
      next.push_back({tri[2], c, b});
      next.push_back({a, b, c});
    }
    f = std::move(next);
  }
  Mesh mesh;
  for (const Vec3& p : v) mesh.vertices_O.push_back(p * (radius / norm(p)));
  mesh.triangles = f;
  return mesh;
}

/// A soup of n random, separate, non-degenerate triangles in a 0.2 m cube.
Mesh random_soup(std::mt19937& rng, int n) {
  std::uniform_real_distribution<double> u(-0.1, 0.1);
  std::uniform_real_distribution<double> small(-0.02, 0.02);
  Mesh mesh;
  while (static_cast<int>(mesh.triangles.size()) < n) {
    const Vec3 c{u(rng), u(rng), u(rng)};
    const Vec3 a = c + Vec3{small(rng), small(rng), small(rng)};
    const Vec3 b = c + Vec3{small(rng), small(rng), small(rng)};
    const Vec3 d = c + Vec3{small(rng), small(rng), small(rng)};
    if (norm(cross(b - a, d - a)) < 1e-6) continue;
    const auto i = static_cast<std::uint32_t>(mesh.vertices_O.size());
    mesh.vertices_O.insert(mesh.vertices_O.end(), {a, b, d});
    mesh.triangles.push_back({i, i + 1, i + 2});
  }
  return mesh;
}

bool near(const Vec3& a, const Vec3& b, double tol) { return norm(a - b) <= tol; }

// ---------------------------------------------------------------------------------------------
// Validation

TEST(MeshValidation, AcceptsAPlateAClosedSphereAndOpenCorners) {
  EXPECT_EQ(validate_mesh(plate(), 100), "");
  EXPECT_EQ(validate_mesh(icosphere(0.05, 2), 320), "");
  EXPECT_EQ(validate_mesh(corner_edge(), 100), "");
  EXPECT_EQ(validate_mesh(corner_vertex(), 100), "");
}

TEST(MeshValidation, RejectsEachBadCaseNamingTheElement) {
  EXPECT_EQ(validate_mesh(Mesh{}, 100), "triangles: empty mesh (no triangles)");
  EXPECT_EQ(validate_mesh(icosphere(0.05, 1), 79),
            "triangles: 80 triangles exceed the limit of 79");
  {
    Mesh m = plate();
    m.vertices_O.resize(7);  // 4 used + 3 unused vertices: over 3 per allowed triangle
    EXPECT_EQ(validate_mesh(m, 2),
              "vertices_O: 7 vertices exceed the limit of 6 (3 per allowed triangle)");
    EXPECT_EQ(validate_mesh(m, 3), "");  // unused vertices are allowed
  }
  {
    Mesh m = plate();
    m.vertices_O[2].y = std::nan("");
    EXPECT_EQ(validate_mesh(m, 100), "vertices_O[2]: not finite (0.1, nan, 0)");
    m.vertices_O[2].y = INFINITY;
    EXPECT_EQ(validate_mesh(m, 100), "vertices_O[2]: not finite (0.1, inf, 0)");
    m.vertices_O[2].y = 2000.0;
    EXPECT_EQ(validate_mesh(m, 100), "vertices_O[2]: (0.1, 2000, 0) m outside +-1000 m");
  }
  {
    Mesh m = plate();
    m.triangles[1][2] = 4;
    EXPECT_EQ(validate_mesh(m, 100), "triangles[1]: vertex index 4 out of range (4 vertices)");
  }
  {
    Mesh m = plate();
    m.triangles[1] = {0, 2, 2};  // repeated vertex
    EXPECT_EQ(validate_mesh(m, 100), "triangles[1]: zero area (vertices 0, 2, 2)");
    m.vertices_O.push_back({0.05, 0.05, 0.0});  // on the diagonal 0 -> 2: collinear
    m.triangles[1] = {0, 2, 4};
    EXPECT_EQ(validate_mesh(m, 100), "triangles[1]: zero area (vertices 0, 2, 4)");
    m.vertices_O[4] = m.vertices_O[0];  // coincident with vertex 0
    EXPECT_EQ(validate_mesh(m, 100), "triangles[1]: zero area (vertices 0, 2, 4)");
  }
  {
    Mesh m = plate();
    m.triangles.push_back({2, 0, 1});  // triangles[0] again, rotated
    EXPECT_EQ(validate_mesh(m, 100), "triangles[2]: repeats triangles[0] (vertices 0, 1, 2)");
  }
  {
    // Three plates on the edge (0, 1): a book with three pages.
    Mesh m;
    m.vertices_O = {{0, 0, 0}, {0.1, 0, 0}, {0, 0.1, 0}, {0, -0.1, 0}, {0, 0, 0.1}};
    m.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
    EXPECT_EQ(validate_mesh(m, 100),
              "edge (0, 1): non-manifold, shared by 3 triangles (triangles[0], triangles[1], "
              "triangles[2])");
  }
  {
    Mesh m = plate();
    m.triangles[1] = {0, 3, 2};  // flipped: both triangles now traverse 2 -> 0
    EXPECT_EQ(validate_mesh(m, 100),
              "edge (0, 2): inconsistent winding, triangles[0] and triangles[1] both traverse "
              "2 -> 0");
  }
}

// ---------------------------------------------------------------------------------------------
// Primitives and the BVH

TEST(MeshPrimitives, ClosestPointOnTriangleMatchesDenseSampling) {
  // Ericson 2005, sec. 5.1.5: checked against the minimum over a 200 x 200 barycentric grid.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.1, 0.1);
  for (int trial = 0; trial < 40; ++trial) {
    const Vec3 a{u(rng), u(rng), u(rng)}, b{u(rng), u(rng), u(rng)}, c{u(rng), u(rng), u(rng)};
    const Vec3 p{2 * u(rng), 2 * u(rng), 2 * u(rng)};
    const Vec3 q = closest_point_on_triangle(p, a, b, c);
    double sampled = INFINITY;
    constexpr int kN = 200;
    for (int i = 0; i <= kN; ++i) {
      for (int j = 0; i + j <= kN; ++j) {
        const double s = double(i) / kN, t = double(j) / kN;
        sampled = std::min(sampled, norm(a + s * (b - a) + t * (c - a) - p));
      }
    }
    EXPECT_LE(norm(q - p), sampled + 1e-15);                // never worse than any sample
    EXPECT_GE(norm(q - p), sampled - 0.3 * 0.4 / kN * 2);   // and within the grid's spacing
  }
}

TEST(MeshPrimitives, SegmentHitsBothSidesAndMissesBesideTheTriangle) {
  const Vec3 a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
  double t = -1.0;
  EXPECT_TRUE(segment_hits_triangle({0.2, 0.2, 1}, {0.2, 0.2, -3}, a, b, c, t));
  EXPECT_DOUBLE_EQ(t, 0.25);
  EXPECT_TRUE(segment_hits_triangle({0.2, 0.2, -1}, {0.2, 0.2, 1}, a, b, c, t));  // back side
  EXPECT_DOUBLE_EQ(t, 0.5);
  EXPECT_FALSE(segment_hits_triangle({0.8, 0.8, 1}, {0.8, 0.8, -1}, a, b, c, t));  // beside
  EXPECT_FALSE(segment_hits_triangle({0.2, 0.2, 1}, {0.2, 0.2, 0.1}, a, b, c, t));  // short
  EXPECT_FALSE(segment_hits_triangle({0.1, 0.1, 0}, {0.3, 0.1, 0}, a, b, c, t));  // in plane
  EXPECT_TRUE(segment_hits_triangle({0.5, 0.5, 1}, {0.5, 0.5, -1}, a, b, c, t));  // on the edge
}

/// Brute force over every triangle with the public primitives.
ClosestPointResult brute_closest(const Mesh& m, const Vec3& p, double radius) {
  ClosestPointResult best;
  for (std::uint32_t i = 0; i < m.triangles.size(); ++i) {
    const auto& tri = m.triangles[i];
    const Vec3 q = closest_point_on_triangle(p, m.vertices_O[tri[0]], m.vertices_O[tri[1]],
                                             m.vertices_O[tri[2]]);
    const double d = norm(q - p);
    if (d <= radius && (!best.found || d < best.distance)) {
      best.found = true;
      best.distance = d;
      best.triangle = i;
      best.point_O = q;
    }
  }
  return best;
}

SegmentHitResult brute_hit(const Mesh& m, const Vec3& p0, const Vec3& p1) {
  SegmentHitResult best;
  for (std::uint32_t i = 0; i < m.triangles.size(); ++i) {
    const auto& tri = m.triangles[i];
    double t = 0.0;
    if (segment_hits_triangle(p0, p1, m.vertices_O[tri[0]], m.vertices_O[tri[1]],
                              m.vertices_O[tri[2]], t) &&
        (!best.hit || t < best.t)) {
      best.hit = true;
      best.t = t;
      best.triangle = i;
    }
  }
  return best;
}

TEST(MeshBvh, ClosestPointAgreesWithBruteForceOnRandomMeshes) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.15, 0.15);
  std::uniform_real_distribution<double> r(0.0, 0.08);
  std::vector<Mesh> meshes = {random_soup(rng, 500), random_soup(rng, 37), icosphere(0.07, 3)};
  for (const Mesh& m : meshes) {
    ASSERT_EQ(validate_mesh(m, 10000), "");
    const MeshBvh bvh = MeshBvh::build(m);
    ASSERT_EQ(bvh.triangle_count(), m.triangles.size());
    int found = 0;
    for (int i = 0; i < 2000; ++i) {
      const Vec3 p{u(rng), u(rng), u(rng)};
      const double radius = i % 4 == 0 ? INFINITY : r(rng);
      const ClosestPointResult fast = bvh.closest_point(p, radius);
      const ClosestPointResult slow = brute_closest(m, p, radius);
      ASSERT_EQ(fast.found, slow.found) << "point " << i;
      if (!slow.found) continue;
      ++found;
      EXPECT_NEAR(fast.distance, slow.distance, 1e-15);
      EXPECT_NEAR(norm(fast.point_O - p), fast.distance, 1e-15);
      if (fast.triangle != slow.triangle) {  // only on an exact tie (a shared edge or vertex)
        EXPECT_TRUE(near(fast.point_O, slow.point_O, 1e-12));
      }
    }
    EXPECT_GT(found, 500);  // the radii both found and missed
    EXPECT_LT(found, 2000);
  }
}

TEST(MeshBvh, FirstHitAgreesWithBruteForceOnRandomSegments) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> u(-0.15, 0.15);
  std::vector<Mesh> meshes = {random_soup(rng, 500), icosphere(0.07, 3), plate()};
  for (const Mesh& m : meshes) {
    const MeshBvh bvh = MeshBvh::build(m);
    int hits = 0;
    for (int i = 0; i < 3000; ++i) {
      const Vec3 p0{u(rng), u(rng), u(rng)};
      Vec3 p1{u(rng), u(rng), u(rng)};
      if (i % 5 == 0) p1 = {p0.x, p0.y, p1.z};  // axis-parallel: zero slab directions
      const SegmentHitResult fast = bvh.first_hit(p0, p1);
      const SegmentHitResult slow = brute_hit(m, p0, p1);
      ASSERT_EQ(fast.hit, slow.hit) << "segment " << i;
      if (!slow.hit) continue;
      ++hits;
      EXPECT_EQ(fast.t, slow.t);
      EXPECT_EQ(fast.triangle, slow.triangle);  // ties go to the lowest index in both
      EXPECT_TRUE(near(fast.point_O, p0 + fast.t * (p1 - p0), 0.0));
    }
    EXPECT_GT(hits, 100);
    EXPECT_LT(hits, 3000);
  }
}

TEST(MeshBvh, DepthStaysWithinTheFixedStackBound) {
  std::mt19937 rng(17);
  for (int n : {1, 4, 5, 37, 1000, 5000}) {
    const MeshBvh bvh = MeshBvh::build(random_soup(rng, n));
    const double bound = n <= 4 ? 1.0 : std::ceil(std::log2(n / 4.0)) + 1.0;
    EXPECT_LE(bvh.depth(), bound) << n;
    EXPECT_LE(bvh.depth() + 1, MeshBvh::kStackSize);
    EXPECT_LE(bvh.node_count(), 2u * static_cast<unsigned>(n));
  }
  const MeshBvh empty;
  EXPECT_FALSE(empty.first_hit({0, 0, 1}, {0, 0, -1}).hit);
  EXPECT_FALSE(empty.closest_point({0, 0, 0}, INFINITY).found);
}

// ---------------------------------------------------------------------------------------------
// God object

TEST(GodObject, FreeSpaceGivesZeroForceAndTheProxyAtTheTool) {
  const MeshBvh bvh = MeshBvh::build(plate());
  const MeshPose pose{{0.01, -0.02, 0.003}, {0.9238795325112867, 0.3826834323650898, 0, 0}, {}, {}};
  GodObjectState state;
  for (int i = 0; i < 100; ++i) {
    // Around above the (rotated) plate, and beside it, never through it.
    const Vec3 p_WT{0.3 * std::sin(i * 0.1), 0.3 * std::cos(i * 0.1), 0.2 + 0.01 * i};
    const GodObjectOutput out = update_god_object(state, bvh, pose, params(5.0), p_WT, {1, 2, 3});
    EXPECT_EQ(out.F_T_W, Vec3{});
    EXPECT_EQ(out.p_WP, p_WT);
    EXPECT_FALSE(out.in_contact);
    EXPECT_EQ(out.plane_count, 0u);
    EXPECT_FALSE(state.in_contact);
  }
}

TEST(GodObject, AFastToolCannotPassThroughAThinPlateFromAbove) {
  const MeshBvh bvh = MeshBvh::build(plate());
  const MeshPose pose;
  GodObjectState state;
  update_god_object(state, bvh, pose, params(), {0.01, 0.02, 0.01}, {});
  // One tick from 10 mm above to 50 mm below: the segment crosses the plate.
  GodObjectOutput out = update_god_object(state, bvh, pose, params(), {0.01, 0.02, -0.05}, {});
  EXPECT_TRUE(out.in_contact);
  EXPECT_NEAR(out.p_WP.z, kMargin, 1e-15);
  EXPECT_NEAR(out.p_WP.x, 0.01, 1e-15);
  EXPECT_NEAR(out.F_T_W.z, kK * (0.05 + kMargin), 1e-9);
  EXPECT_NEAR(std::hypot(out.F_T_W.x, out.F_T_W.y), 0.0, 1e-12);
  ASSERT_EQ(out.plane_count, 1u);
  EXPECT_TRUE(near(out.normals_W[0], {0, 0, 1}, 1e-15));
  // Deeper still and sliding under the plate: held on top, following the tool's projection.
  for (int i = 0; i < 50; ++i) {
    const Vec3 p_WT{0.01 - 0.002 * i, 0.02, -0.08};
    out = update_god_object(state, bvh, pose, params(), p_WT, {});
    EXPECT_NEAR(out.p_WP.z, kMargin, 1e-15);
    EXPECT_NEAR(out.p_WP.x, p_WT.x, 1e-12);
    EXPECT_NEAR(out.F_T_W.z, kK * (0.08 + kMargin), 1e-9);
  }
}

TEST(GodObject, AFastToolCannotPassThroughAThinPlateFromBelow) {
  const MeshBvh bvh = MeshBvh::build(plate());
  const MeshPose pose;
  GodObjectState state;
  update_god_object(state, bvh, pose, params(), {-0.03, 0.0, -0.01}, {});
  const GodObjectOutput out =
      update_god_object(state, bvh, pose, params(), {-0.03, 0.0, 0.2}, {});
  EXPECT_TRUE(out.in_contact);
  EXPECT_NEAR(out.p_WP.z, -kMargin, 1e-15);
  EXPECT_NEAR(out.F_T_W.z, -kK * (0.2 + kMargin), 1e-9);
  ASSERT_EQ(out.plane_count, 1u);
  EXPECT_TRUE(near(out.normals_W[0], {0, 0, -1}, 1e-15));  // the underside faces down
}

TEST(GodObject, AToolGoingAroundThePlatesEdgeIsReleased) {
  const MeshBvh bvh = MeshBvh::build(plate(0.0, 0.1));
  const MeshPose pose;
  GodObjectState state;
  update_god_object(state, bvh, pose, params(), {0.05, 0, 0.01}, {});
  update_god_object(state, bvh, pose, params(), {0.05, 0, -0.01}, {});
  ASSERT_TRUE(state.in_contact);
  // Beyond the edge (x = 0.1) under the plate's height: the proxy slides off and joins the tool.
  GodObjectOutput out = update_god_object(state, bvh, pose, params(), {0.12, 0, -0.01}, {});
  EXPECT_FALSE(out.in_contact);
  EXPECT_EQ(out.F_T_W, Vec3{});
  // Back under the plate from beside: now held on the underside.
  out = update_god_object(state, bvh, pose, params(), {0.05, 0, 0.01}, {});
  EXPECT_TRUE(out.in_contact);
  EXPECT_NEAR(out.p_WP.z, -kMargin, 1e-12);
  EXPECT_LT(out.F_T_W.z, 0.0);
}

TEST(GodObject, SlidingAlongAConcaveEdgePushesAlongBothNormals) {
  const MeshBvh bvh = MeshBvh::build(corner_edge());
  const MeshPose pose;
  GodObjectState state;
  update_god_object(state, bvh, pose, params(), {0.03, -0.05, 0.03}, {});
  for (int i = 0; i <= 40; ++i) {
    const double y = -0.05 + 0.0025 * i;
    const Vec3 p_WT{-0.004, y, -0.007};
    const GodObjectOutput out = update_god_object(state, bvh, pose, params(), p_WT, {});
    ASSERT_TRUE(out.in_contact);
    EXPECT_TRUE(near(out.p_WP, {kMargin, y, kMargin}, 1e-12)) << i;
    // F = K (p_WP - p_WT): +x from the wall, +z from the floor, none along the edge.
    EXPECT_NEAR(out.F_T_W.x, kK * (0.004 + kMargin), 1e-9);
    EXPECT_NEAR(out.F_T_W.z, kK * (0.007 + kMargin), 1e-9);
    EXPECT_NEAR(out.F_T_W.y, 0.0, 1e-9);
    EXPECT_EQ(out.plane_count, 2u);
    EXPECT_LE(out.iterations, kGodObjectMaxIterations);
  }
  // Out of the corner along the floor only: one plane, force +z only.
  const GodObjectOutput out = update_god_object(state, bvh, pose, params(), {0.05, 0, -0.002}, {});
  EXPECT_TRUE(near(out.p_WP, {0.05, 0, kMargin}, 1e-12));
  EXPECT_NEAR(out.F_T_W.x, 0.0, 1e-9);
  EXPECT_NEAR(out.F_T_W.z, kK * (0.002 + kMargin), 1e-9);
  EXPECT_EQ(out.plane_count, 1u);
}

TEST(GodObject, PushingIntoAConcaveVertexHoldsTheProxyOnThreePlanes) {
  const MeshBvh bvh = MeshBvh::build(corner_vertex());
  const MeshPose pose;
  GodObjectState state;
  update_god_object(state, bvh, pose, params(), {0.02, 0.03, 0.04}, {});
  const Vec3 p_WT{-0.01, -0.02, -0.03};
  const GodObjectOutput out = update_god_object(state, bvh, pose, params(), p_WT, {});
  ASSERT_TRUE(out.in_contact);
  EXPECT_TRUE(near(out.p_WP, {kMargin, kMargin, kMargin}, 1e-12));
  EXPECT_TRUE(near(out.F_T_W, kK * (Vec3{kMargin, kMargin, kMargin} - p_WT), 1e-9));
  EXPECT_EQ(out.plane_count, 3u);
  // Releasing one wall: the tool slides out along y, the proxy leaves the y = 0 wall.
  const GodObjectOutput two =
      update_god_object(state, bvh, pose, params(), {-0.01, 0.05, -0.03}, {});
  EXPECT_TRUE(near(two.p_WP, {kMargin, 0.05, kMargin}, 1e-12));
  EXPECT_EQ(two.plane_count, 2u);
  EXPECT_NEAR(two.F_T_W.y, 0.0, 1e-9);
}

TEST(GodObject, ProxyStaysOnAFacetedSphereAcrossEdgesAndVertices) {
  const Mesh sphere = icosphere(0.05, 3);  // 1280 facets
  const MeshBvh bvh = MeshBvh::build(sphere);
  const MeshPose pose{{0.1, 0.0, 0.0}, {}, {}, {}};
  GodObjectState state;
  std::uint32_t max_iterations = 0;
  for (int i = 0; i <= 2000; ++i) {
    // Approach from outside, then circle 5 mm inside the surface on a tilted great circle,
    // about 0.8 mm per tick, crossing facet edges and vertices.
    const double a = 0.016 * i;
    const double r = i < 20 ? 0.07 - 0.001 * i : 0.045;
    const Vec3 dir{std::cos(a), std::sin(a) * 0.8, std::sin(a) * 0.6};
    const Vec3 p_WT = pose.p_WO + r * dir;
    const GodObjectOutput out = update_god_object(state, bvh, pose, params(), p_WT, {});
    max_iterations = std::max(max_iterations, out.iterations);
    if (i < 20) continue;
    ASSERT_TRUE(out.in_contact) << i;
    const Vec3 p_OP = out.p_WP - pose.p_WO;
    const ClosestPointResult c = bvh.closest_point(p_OP, INFINITY);
    // Outside every facet, by about the margin, never inside the solid.
    ASSERT_GE(dot(p_OP - c.point_O, c.normal_O), 0.0) << i;
    EXPECT_GE(c.distance, 0.5 * kMargin) << i;
    EXPECT_LE(c.distance, 2.0 * kMargin) << i;
    // The force pushes outward and is the spring to the proxy.
    EXPECT_GT(dot(out.F_T_W, dir), 0.0);
    EXPECT_TRUE(near(out.F_T_W, kK * (out.p_WP - p_WT), 1e-9));
  }
  // The bound was never reached: every tick converged rather than being cut off.
  EXPECT_LT(max_iterations, kGodObjectMaxIterations);
}

TEST(GodObject, AMovingPlateCarriesTheProxyAndPushesAStillTool) {
  const MeshBvh bvh = MeshBvh::build(plate());
  GodObjectState state;
  const Vec3 p_WT{0.02, 0.01, 0.005};
  MeshPose pose;
  for (int i = 0; i <= 10; ++i) {
    // The plate rises 1 mm per tick from z = 0 through the still tool at z = 5 mm.
    pose.p_WO = {0, 0, 0.001 * i};
    pose.v_WO = {0, 0, 1.0};
    const GodObjectOutput out = update_god_object(state, bvh, pose, params(), p_WT, {});
    if (i <= 4) {
      EXPECT_FALSE(out.in_contact) << i;
      continue;
    }
    // Since it passed the tool, the proxy rides on top: the tool is pushed up.
    ASSERT_TRUE(out.in_contact) << i;
    EXPECT_NEAR(out.p_WP.z, 0.001 * i + kMargin, 1e-15);
    EXPECT_NEAR(out.F_T_W.z, kK * (0.001 * i + kMargin - 0.005), 1e-9);
  }
  // A plate turned +90 degrees about x (q = (cos 45, sin 45, 0, 0) maps O's +z to W's -y): the
  // tool pushed in from the -y side is held there, and the force lies along W's -y.
  const double h = std::sqrt(0.5);
  pose = {{0, 0, 0}, {h, h, 0, 0}, {}, {}};
  GodObjectState tilted;
  update_god_object(tilted, bvh, pose, params(), {0.01, -0.01, 0.02}, {});  // in front (-y side)
  const GodObjectOutput out =
      update_god_object(tilted, bvh, pose, params(), {0.01, 0.03, 0.02}, {});
  ASSERT_TRUE(out.in_contact);
  EXPECT_NEAR(out.p_WP.y, -kMargin, 1e-12);
  EXPECT_NEAR(out.F_T_W.y, -kK * (0.03 + kMargin), 1e-9);
  EXPECT_NEAR(out.F_T_W.z, 0.0, 1e-9);
}

TEST(GodObject, DampingActsOnTheApproachSpeedRelativeToTheSurfaceAndNeverPulls) {
  const MeshBvh bvh = MeshBvh::build(plate());
  MeshPose pose;
  GodObjectState state;
  update_god_object(state, bvh, pose, params(10.0), {0, 0, 0.01}, {});
  // Pressing in at 0.1 m/s: F = K d + B v = 1000 * 0.002 + 10 * 0.1 (plus the margin's share).
  GodObjectOutput out = update_god_object(state, bvh, pose, params(10.0), {0, 0, -0.002},
                                          {0.5, 0, -0.1});
  EXPECT_NEAR(out.F_T_W.z, kK * (0.002 + kMargin) + 10.0 * 0.1, 1e-9);
  EXPECT_NEAR(out.F_T_W.x, 0.0, 1e-12);  // sliding speed is not damped here
  // The same tool velocity while the plate moves down at 0.1 m/s: no relative approach.
  pose.v_WO = {0, 0, -0.1};
  out = update_god_object(state, bvh, pose, params(10.0), {0, 0, -0.002}, {0, 0, -0.1});
  EXPECT_NEAR(out.F_T_W.z, kK * (0.002 + kMargin), 1e-9);
  // Leaving fast: the damper would pull; the force is clamped at zero instead.
  pose.v_WO = {};
  out = update_god_object(state, bvh, pose, params(10.0), {0, 0, -0.002}, {0, 0, 5.0});
  EXPECT_EQ(out.F_T_W, Vec3{});
  EXPECT_TRUE(out.in_contact);
}

TEST(GodObject, ReplacingTheMeshWhileTouchedChangesTheForceOnlyByTheGeometryChange) {
  const GodObjectParams p = params();
  const MeshPose pose;
  const Vec3 p_WT{0.01, 0.01, -0.002};
  const auto pressed = [&](GodObjectState& state, const MeshBvh& bvh) {
    update_god_object(state, bvh, pose, p, {0.01, 0.01, 0.01}, {});
    return update_god_object(state, bvh, pose, p, p_WT, {});
  };
  const MeshBvh old_plate = MeshBvh::build(plate(0.0));
  for (const double shift : {0.0, 0.001, -0.001, 0.015, -0.0015}) {
    GodObjectState state;
    const GodObjectOutput before = pressed(state, old_plate);
    ASSERT_NEAR(before.F_T_W.z, kK * (0.002 + kMargin), 1e-9);
    const MeshBvh new_plate = MeshBvh::build(plate(shift));
    rebase_god_object(state, new_plate, pose, p);
    const GodObjectOutput after = update_god_object(state, new_plate, pose, p, p_WT, {});
    const double jump = norm(after.F_T_W - before.F_T_W);
    // The surface moved by |shift| along the contact normal: the force follows it, no more.
    EXPECT_LE(jump, kK * (std::abs(shift) + kMargin) + 1e-9) << shift;
    if (shift > -0.002) {  // the new surface is still above the tool: held on it
      EXPECT_NEAR(after.p_WP.z, shift + kMargin, 1e-12) << shift;
      EXPECT_NEAR(after.F_T_W.z, kK * (0.002 + shift + kMargin), 1e-9) << shift;
    }
  }
  {
    // Receded below the tool: free, the force goes to zero (a jump of K * 2 mm, what it implies).
    GodObjectState state;
    pressed(state, old_plate);
    const MeshBvh lower = MeshBvh::build(plate(-0.003));
    rebase_god_object(state, lower, pose, p);
    const GodObjectOutput after = update_god_object(state, lower, pose, p, p_WT, {});
    EXPECT_FALSE(after.in_contact);
    EXPECT_EQ(after.F_T_W, Vec3{});
  }
  {
    // A sphere replaced by one 0.5 mm larger, pressed 3 mm in: the jump stays within
    // K (0.5 mm + margin + the facets' sagitta where the contact lands).
    const MeshBvh small = MeshBvh::build(icosphere(0.05, 3));
    const MeshBvh large = MeshBvh::build(icosphere(0.0505, 3));
    const Vec3 dir = Vec3{0.3, 0.4, 0.866} * (1.0 / norm(Vec3{0.3, 0.4, 0.866}));
    GodObjectState state;
    update_god_object(state, small, pose, p, 0.06 * dir, {});
    const GodObjectOutput before = update_god_object(state, small, pose, p, 0.047 * dir, {});
    ASSERT_TRUE(before.in_contact);
    rebase_god_object(state, large, pose, p);
    const GodObjectOutput after = update_god_object(state, large, pose, p, 0.047 * dir, {});
    ASSERT_TRUE(after.in_contact);
    const double sagitta = 0.0505 * (1.0 - std::cos(0.5 * 0.1));  // edge angle < 0.1 rad
    EXPECT_LE(norm(after.F_T_W - before.F_T_W), kK * (0.0005 + kMargin + sagitta));
    EXPECT_GT(norm(after.F_T_W), norm(before.F_T_W));  // the grown surface pushes harder
  }
  {
    // Without the rebase the old object-frame proxy would lie under the raised plate: the proxy
    // there is free to reach the tool, and contact (and force) would be lost.
    GodObjectState state;
    pressed(state, old_plate);
    const MeshBvh raised = MeshBvh::build(plate(0.001));
    const GodObjectOutput naive = update_god_object(state, raised, pose, p, p_WT, {});
    EXPECT_FALSE(naive.in_contact);
  }
}

TEST(GodObject, NonFiniteInputGivesZeroForceAndKeepsTheState) {
  const MeshBvh bvh = MeshBvh::build(plate());
  const MeshPose pose;
  GodObjectState state;
  update_god_object(state, bvh, pose, params(), {0, 0, 0.01}, {});
  update_god_object(state, bvh, pose, params(), {0, 0, -0.01}, {});
  const Vec3 p_OP = state.p_OP;
  GodObjectOutput out = update_god_object(state, bvh, pose, params(), {0, std::nan(""), 0}, {});
  EXPECT_TRUE(out.input_rejected);
  EXPECT_EQ(out.F_T_W, Vec3{});
  EXPECT_EQ(state.p_OP, p_OP);
  MeshPose bad = pose;
  bad.R_WO = {0, 0, 0, 0};
  out = update_god_object(state, bvh, bad, params(), {0, 0, -0.01}, {});
  EXPECT_TRUE(out.input_rejected);
  EXPECT_EQ(out.F_T_W, Vec3{});
  out = update_god_object(state, bvh, pose, params(), {0, 0, -0.01}, {});
  EXPECT_FALSE(out.input_rejected);
  EXPECT_NEAR(out.F_T_W.z, kK * (0.01 + kMargin), 1e-9);
}

TEST(GodObject, ParameterValidationNamesTheBadParameter) {
  EXPECT_EQ(validate_god_object_params(params(1.0)), "");
  GodObjectParams p = params();
  p.stiffness = -1.0;
  EXPECT_EQ(validate_god_object_params(p), "stiffness: -1 (must be finite and >= 0 N/m)");
  p = params();
  p.damping = std::nan("");
  EXPECT_EQ(validate_god_object_params(p), "damping: nan (must be finite and >= 0 N*s/m)");
  p = params();
  p.margin = 0.0;
  EXPECT_EQ(validate_god_object_params(p), "margin: 0 (must be in (0, 1e-3] m)");
  p = params();
  p.replace_lift = INFINITY;
  EXPECT_EQ(validate_god_object_params(p), "replace_lift: inf (must be finite and >= 0 m)");
}

TEST(GodObject, TicksAndRebasesAllocateNothing) {
  // The per-tick working set is fixed: four constraint planes on the stack in
  // update_god_object and a 64-entry node stack in each BVH query.
  const MeshBvh sphere = MeshBvh::build(icosphere(0.05, 3));
  const MeshBvh other = MeshBvh::build(icosphere(0.051, 3));
  const MeshPose pose;
  GodObjectState state;
  std::uint32_t contacts = 0;
  haptic::test::reset_allocations();
  {
    haptic::test::CountAllocations counting;
    for (int i = 0; i < 1000; ++i) {
      const double a = 0.01 * i;
      const Vec3 p_WT = (0.045 + 0.01 * std::sin(0.05 * i)) *
                        Vec3{std::cos(a), std::sin(a) * 0.6, std::sin(a) * 0.8};
      const MeshBvh& mesh = (i / 100) % 2 == 0 ? sphere : other;
      if (i % 100 == 0) rebase_god_object(state, mesh, pose, params());
      const GodObjectOutput out = update_god_object(state, mesh, pose, params(1.0), p_WT, {});
      contacts += out.in_contact ? 1 : 0;
      contacts += mesh.closest_point(p_WT, 0.01).found ? 0 : 0;
    }
  }
  EXPECT_EQ(haptic::test::allocations(), 0u);
  EXPECT_GT(contacts, 100u);
}

}  // namespace
}  // namespace haptic::engine
