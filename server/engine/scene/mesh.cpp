#include "engine/scene/mesh.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <tuple>

namespace haptic::engine {
namespace {

std::string format(const char* fmt, auto... args) {
  char buffer[256];
  std::snprintf(buffer, sizeof buffer, fmt, args...);
  return buffer;
}

Vec3 unit_normal(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = cross(b - a, c - a);
  return n * (1.0 / norm(n));
}

/// The shared crossing test (see segment_hits_triangle in the header), with the triangle's unit
/// normal n and plane offset dot(n, a) given.
bool crosses(const Vec3& p0, const Vec3& p1, const Vec3& a, const Vec3& b, const Vec3& c,
             const Vec3& n, double offset, double& t) {
  const double d0 = dot(n, p0) - offset;
  const double d1 = dot(n, p1) - offset;
  if ((d0 > 0.0 && d1 > 0.0) || (d0 < 0.0 && d1 < 0.0) || (d0 == 0.0 && d1 == 0.0)) return false;
  const double s = d0 / (d0 - d1);
  const Vec3 q = p0 + s * (p1 - p0);
  // Barycentric coordinates of q (Ericson 2005, sec. 3.4, Barycentric()).
  const Vec3 v0 = b - a;
  const Vec3 v1 = c - a;
  const Vec3 v2 = q - a;
  const double d00 = dot(v0, v0);
  const double d01 = dot(v0, v1);
  const double d11 = dot(v1, v1);
  const double d20 = dot(v2, v0);
  const double d21 = dot(v2, v1);
  const double denominator = d00 * d11 - d01 * d01;
  const double v = (d11 * d20 - d01 * d21) / denominator;
  const double w = (d00 * d21 - d01 * d20) / denominator;
  const double u = 1.0 - v - w;
  if (!(u >= -kBarycentricTolerance && v >= -kBarycentricTolerance &&
        w >= -kBarycentricTolerance)) {
    return false;
  }
  t = std::clamp(s, 0.0, 1.0);
  return true;
}

Aabb empty_box() {
  constexpr double inf = std::numeric_limits<double>::infinity();
  return {{inf, inf, inf}, {-inf, -inf, -inf}};
}

void grow(Aabb& box, const Vec3& p) {
  box.min = {std::min(box.min.x, p.x), std::min(box.min.y, p.y), std::min(box.min.z, p.z)};
  box.max = {std::max(box.max.x, p.x), std::max(box.max.y, p.y), std::max(box.max.z, p.z)};
}

void grow(Aabb& box, const Aabb& other) {
  grow(box, other.min);
  grow(box, other.max);
}

double axis(const Vec3& v, int i) { return i == 0 ? v.x : (i == 1 ? v.y : v.z); }

/// Squared distance from p to the box (0 inside). Unit: m^2.
double distance_squared(const Aabb& box, const Vec3& p) {
  const double dx = std::max({box.min.x - p.x, 0.0, p.x - box.max.x});
  const double dy = std::max({box.min.y - p.y, 0.0, p.y - box.max.y});
  const double dz = std::max({box.min.z - p.z, 0.0, p.z - box.max.z});
  return dx * dx + dy * dy + dz * dz;
}

/// Whether the segment p0 + s d, s in [0, s_max], meets the box (slab test, Kay and Kajiya 1986;
/// an axis the segment runs parallel to is tested by containment, so no 0 * inf arises).
bool segment_meets_box(const Aabb& box, const Vec3& p0, const Vec3& d, double s_max) {
  double lo = 0.0;
  double hi = s_max;
  for (int i = 0; i < 3; ++i) {
    const double o = axis(p0, i);
    const double di = axis(d, i);
    const double bmin = axis(box.min, i);
    const double bmax = axis(box.max, i);
    if (di == 0.0) {
      if (o < bmin || o > bmax) return false;
      continue;
    }
    double s0 = (bmin - o) / di;
    double s1 = (bmax - o) / di;
    if (s0 > s1) std::swap(s0, s1);
    lo = std::max(lo, s0);
    hi = std::min(hi, s1);
    if (lo > hi) return false;
  }
  return true;
}

}  // namespace

std::string validate_mesh(const Mesh& mesh, std::size_t max_triangles) {
  const std::size_t vertex_count = mesh.vertices_O.size();
  const std::size_t triangle_count = mesh.triangles.size();
  if (triangle_count == 0) return "triangles: empty mesh (no triangles)";
  // The hierarchy indexes triangles and nodes with 32 bits: at most 2^31 - 1 triangles.
  const std::size_t triangle_limit = std::min<std::size_t>(max_triangles, 0x7fffffff);
  if (triangle_count > triangle_limit) {
    return format("triangles: %zu triangles exceed the limit of %zu", triangle_count,
                  triangle_limit);
  }
  const std::size_t vertex_limit = 3 * triangle_limit;
  if (vertex_count > vertex_limit) {
    return format("vertices_O: %zu vertices exceed the limit of %zu (3 per allowed triangle)",
                  vertex_count, vertex_limit);
  }
  for (std::size_t i = 0; i < vertex_count; ++i) {
    const Vec3& v = mesh.vertices_O[i];
    if (!is_finite(v)) return format("vertices_O[%zu]: not finite (%g, %g, %g)", i, v.x, v.y, v.z);
    if (std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)}) > kMaxMeshCoordinate) {
      return format("vertices_O[%zu]: (%g, %g, %g) m outside +-%g m", i, v.x, v.y, v.z,
                    kMaxMeshCoordinate);
    }
  }
  for (std::size_t i = 0; i < triangle_count; ++i) {
    const auto& tri = mesh.triangles[i];
    for (int k = 0; k < 3; ++k) {
      if (tri[k] >= vertex_count) {
        return format("triangles[%zu]: vertex index %u out of range (%zu vertices)", i, tri[k],
                      vertex_count);
      }
    }
    const Vec3& a = mesh.vertices_O[tri[0]];
    const Vec3& b = mesh.vertices_O[tri[1]];
    const Vec3& c = mesh.vertices_O[tri[2]];
    const double longest =
        std::max({dot(b - a, b - a), dot(c - b, c - b), dot(a - c, a - c)});
    const double twice_area = norm(cross(b - a, c - a));
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] ||
        !(twice_area > kMinTriangleShape * longest)) {
      return format("triangles[%zu]: zero area (vertices %u, %u, %u)", i, tri[0], tri[1], tri[2]);
    }
  }

  // Repeated triangles: sort the sorted index triples.
  {
    std::vector<std::pair<std::array<std::uint32_t, 3>, std::uint32_t>> keys(triangle_count);
    for (std::size_t i = 0; i < triangle_count; ++i) {
      auto key = mesh.triangles[i];
      std::sort(key.begin(), key.end());
      keys[i] = {key, static_cast<std::uint32_t>(i)};
    }
    std::sort(keys.begin(), keys.end());
    for (std::size_t i = 1; i < triangle_count; ++i) {
      if (keys[i].first == keys[i - 1].first) {
        const auto& k = keys[i].first;
        return format("triangles[%u]: repeats triangles[%u] (vertices %u, %u, %u)",
                      keys[i].second, keys[i - 1].second, k[0], k[1], k[2]);
      }
    }
  }

  // Edges: (low vertex, high vertex, triangle, direction low -> high), sorted so the users of
  // one edge are adjacent.
  struct Edge {
    std::uint32_t lo, hi, triangle;
    bool forward;
  };
  std::vector<Edge> edges;
  edges.reserve(3 * triangle_count);
  for (std::size_t i = 0; i < triangle_count; ++i) {
    const auto& tri = mesh.triangles[i];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t from = tri[k];
      const std::uint32_t to = tri[(k + 1) % 3];
      edges.push_back({std::min(from, to), std::max(from, to), static_cast<std::uint32_t>(i),
                       from < to});
    }
  }
  std::sort(edges.begin(), edges.end(), [](const Edge& l, const Edge& r) {
    return std::tie(l.lo, l.hi, l.triangle) < std::tie(r.lo, r.hi, r.triangle);
  });
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i + 1;
    while (j < edges.size() && edges[j].lo == edges[i].lo && edges[j].hi == edges[i].hi) ++j;
    const Edge& e = edges[i];
    if (j - i > 2) {
      return format(
          "edge (%u, %u): non-manifold, shared by %zu triangles (triangles[%u], triangles[%u], "
          "triangles[%u]%s)",
          e.lo, e.hi, j - i, e.triangle, edges[i + 1].triangle, edges[i + 2].triangle,
          j - i > 3 ? ", ..." : "");
    }
    if (j - i == 2 && edges[i + 1].forward == e.forward) {
      const std::uint32_t from = e.forward ? e.lo : e.hi;
      const std::uint32_t to = e.forward ? e.hi : e.lo;
      return format(
          "edge (%u, %u): inconsistent winding, triangles[%u] and triangles[%u] both traverse "
          "%u -> %u",
          e.lo, e.hi, e.triangle, edges[i + 1].triangle, from, to);
    }
    i = j;
  }
  return "";
}

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  // Ericson 2005, sec. 5.1.5: Voronoi regions of the vertices, then the edges, then the face.
  const Vec3 ab = b - a;
  const Vec3 ac = c - a;
  const Vec3 ap = p - a;
  const double d1 = dot(ab, ap);
  const double d2 = dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return a;
  const Vec3 bp = p - b;
  const double d3 = dot(ab, bp);
  const double d4 = dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return a + (d1 / (d1 - d3)) * ab;
  const Vec3 cp = p - c;
  const double d5 = dot(ab, cp);
  const double d6 = dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  }
  const double denominator = 1.0 / (va + vb + vc);
  return a + (vb * denominator) * ab + (vc * denominator) * ac;
}

bool segment_hits_triangle(const Vec3& p0, const Vec3& p1, const Vec3& a, const Vec3& b,
                           const Vec3& c, double& t) {
  const Vec3 n = unit_normal(a, b, c);
  return crosses(p0, p1, a, b, c, n, dot(n, a), t);
}

MeshBvh MeshBvh::build(const Mesh& mesh) {
  MeshBvh bvh;
  const std::size_t n = mesh.triangles.size();
  if (n == 0) return bvh;
  assert(n < std::numeric_limits<std::uint32_t>::max() / 2);
  std::vector<Vec3> centroids(n);
  std::vector<Aabb> boxes(n);
  std::vector<std::uint32_t> order(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& tri = mesh.triangles[i];
    const Vec3& a = mesh.vertices_O[tri[0]];
    const Vec3& b = mesh.vertices_O[tri[1]];
    const Vec3& c = mesh.vertices_O[tri[2]];
    centroids[i] = (a + b + c) * (1.0 / 3.0);
    boxes[i] = empty_box();
    grow(boxes[i], a);
    grow(boxes[i], b);
    grow(boxes[i], c);
    order[i] = static_cast<std::uint32_t>(i);
  }
  bvh.nodes_.reserve(2 * n);
  bvh.build_node(order, centroids, boxes, 0, static_cast<std::uint32_t>(n), 1);
  bvh.triangles_.reserve(n);
  for (const std::uint32_t source : order) {
    const auto& tri = mesh.triangles[source];
    Tri t;
    t.a = mesh.vertices_O[tri[0]];
    t.b = mesh.vertices_O[tri[1]];
    t.c = mesh.vertices_O[tri[2]];
    t.normal = unit_normal(t.a, t.b, t.c);
    t.offset = dot(t.normal, t.a);
    t.source = source;
    bvh.triangles_.push_back(t);
  }
  return bvh;
}

std::uint32_t MeshBvh::build_node(std::vector<std::uint32_t>& order,
                                  const std::vector<Vec3>& centroids,
                                  const std::vector<Aabb>& boxes, std::uint32_t begin,
                                  std::uint32_t end, std::uint32_t depth) {
  const auto index = static_cast<std::uint32_t>(nodes_.size());
  nodes_.emplace_back();
  depth_ = std::max(depth_, depth);
  Aabb box = empty_box();
  Aabb centroid_box = empty_box();
  for (std::uint32_t i = begin; i < end; ++i) {
    grow(box, boxes[order[i]]);
    grow(centroid_box, centroids[order[i]]);
  }
  const Vec3 pad{kBoxPadding, kBoxPadding, kBoxPadding};
  box.min -= pad;
  box.max += pad;
  nodes_[index].box = box;
  if (end - begin <= kLeafSize) {
    nodes_[index].first = begin;
    nodes_[index].count = end - begin;
    return index;
  }
  const Vec3 extent = centroid_box.max - centroid_box.min;
  const int split_axis = extent.x >= extent.y && extent.x >= extent.z ? 0
                         : extent.y >= extent.z                       ? 1
                                                                      : 2;
  // Median by count (ties broken by index), so each child holds half and the depth stays
  // logarithmic whatever the geometry.
  const std::uint32_t middle = begin + (end - begin) / 2;
  std::nth_element(order.begin() + begin, order.begin() + middle, order.begin() + end,
                   [&](std::uint32_t l, std::uint32_t r) {
                     const double cl = axis(centroids[l], split_axis);
                     const double cr = axis(centroids[r], split_axis);
                     return cl < cr || (cl == cr && l < r);
                   });
  build_node(order, centroids, boxes, begin, middle, depth + 1);
  const std::uint32_t right = build_node(order, centroids, boxes, middle, end, depth + 1);
  nodes_[index].right = right;
  return index;
}

ClosestPointResult MeshBvh::closest_point(const Vec3& p_O, double radius) const {
  ClosestPointResult result;
  if (nodes_.empty() || !is_finite(p_O) || !(radius >= 0.0)) return result;
  double best = radius * radius;  // Squared; a candidate must not exceed it.
  std::uint32_t stack[kStackSize];  // Fixed: depth <= 31 (see the class comment).
  std::size_t top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (distance_squared(node.box, p_O) > best) continue;
    if (node.count > 0) {
      for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
        const Tri& tri = triangles_[i];
        const Vec3 q = closest_point_on_triangle(p_O, tri.a, tri.b, tri.c);
        const Vec3 d = q - p_O;
        const double d2 = dot(d, d);
        if (d2 < best || (!result.found && d2 <= best)) {
          best = d2;
          result.found = true;
          result.triangle = tri.source;
          result.point_O = q;
          result.normal_O = tri.normal;
        }
      }
      continue;
    }
    const std::uint32_t left = static_cast<std::uint32_t>(&node - nodes_.data()) + 1;
    const std::uint32_t right = node.right;
    // Visit the nearer child first (pushed last).
    if (distance_squared(nodes_[left].box, p_O) <= distance_squared(nodes_[right].box, p_O)) {
      stack[top++] = right;
      stack[top++] = left;
    } else {
      stack[top++] = left;
      stack[top++] = right;
    }
    assert(top <= kStackSize);
  }
  if (result.found) result.distance = std::sqrt(best);
  return result;
}

SegmentHitResult MeshBvh::first_hit(const Vec3& p0_O, const Vec3& p1_O) const {
  SegmentHitResult result;
  if (nodes_.empty() || !is_finite(p0_O) || !is_finite(p1_O)) return result;
  const Vec3 d = p1_O - p0_O;
  double best = 1.0;  // Smallest t so far; boxes beyond it are skipped.
  std::uint32_t stack[kStackSize];  // Fixed: depth <= 31 (see the class comment).
  std::size_t top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const std::uint32_t index = stack[--top];
    const Node& node = nodes_[index];
    if (!segment_meets_box(node.box, p0_O, d, best)) continue;
    if (node.count > 0) {
      for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
        const Tri& tri = triangles_[i];
        double t = 0.0;
        if (!crosses(p0_O, p1_O, tri.a, tri.b, tri.c, tri.normal, tri.offset, t)) continue;
        if (t < best || (!result.hit && t <= best) ||
            (t == best && result.hit && tri.source < result.triangle)) {
          best = t;
          result.hit = true;
          result.t = t;
          result.triangle = tri.source;
          result.normal_O = tri.normal;
          result.plane_offset = tri.offset;
        }
      }
      continue;
    }
    stack[top++] = node.right;
    stack[top++] = index + 1;
    assert(top <= kStackSize);
  }
  if (result.hit) result.point_O = p0_O + result.t * d;
  return result;
}

}  // namespace haptic::engine
