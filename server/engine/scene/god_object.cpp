#include "engine/scene/god_object.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace haptic::engine {
namespace {

/// A constraint n . x >= offset in O (n unit, pointing to the proxy's side).
struct Plane {
  Vec3 n;
  double offset = 0.0;  // Unit: m.
};

/// Slack allowed when checking a QP candidate against a plane. Unit: m. Far below any margin.
constexpr double kFeasibilityTolerance = 1e-10;
/// A target closer than this to the proxy counts as reached. Unit: m.
constexpr double kConvergedDistance = 1e-12;
/// Gram determinants below these are treated as parallel planes (sin^2 of the angle between two
/// normals; the triple product of three).
constexpr double kMinGram2 = 1e-12;
constexpr double kMinTriple = 1e-9;

Quat conjugate(const Quat& q) { return {q.w, -q.x, -q.y, -q.z}; }

bool finite(const Quat& q) {
  return std::isfinite(q.w) && std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) &&
         (q.w != 0.0 || q.x != 0.0 || q.y != 0.0 || q.z != 0.0);
}

Vec3 to_object(const MeshPose& pose, const Vec3& p_W) {
  return rotate(conjugate(pose.R_WO), p_W - pose.p_WO);
}

Vec3 to_world(const MeshPose& pose, const Vec3& p_O) { return pose.p_WO + rotate(pose.R_WO, p_O); }

/// Projection of g onto the intersection of the planes whose indices are in `subset` (as
/// equalities), from the Lagrange conditions x = g + sum lambda_i n_i, n_i . x = c_i (Zilles and
/// Salisbury 1995). Returns false where the planes are (nearly) parallel.
bool project(const Vec3& g, const Plane* planes, const std::uint32_t* subset, std::uint32_t size,
             Vec3& x) {
  if (size == 0) {
    x = g;
    return true;
  }
  if (size == 1) {
    const Plane& p = planes[subset[0]];
    x = g + (p.offset - dot(p.n, g)) * p.n;
    return true;
  }
  if (size == 2) {
    const Plane& p = planes[subset[0]];
    const Plane& q = planes[subset[1]];
    const double k = dot(p.n, q.n);
    const double det = 1.0 - k * k;  // Gram [[1, k], [k, 1]] of unit normals.
    if (det < kMinGram2) return false;
    const double r1 = p.offset - dot(p.n, g);
    const double r2 = q.offset - dot(q.n, g);
    const double l1 = (r1 - k * r2) / det;
    const double l2 = (r2 - k * r1) / det;
    x = g + l1 * p.n + l2 * q.n;
    return true;
  }
  // Three planes meet in a point: x = (c1 n2 x n3 + c2 n3 x n1 + c3 n1 x n2) / (n1 . n2 x n3).
  const Plane& p = planes[subset[0]];
  const Plane& q = planes[subset[1]];
  const Plane& r = planes[subset[2]];
  const Vec3 qr = cross(q.n, r.n);
  const double triple = dot(p.n, qr);
  if (std::abs(triple) < kMinTriple) return false;
  x = (p.offset * qr + q.offset * cross(r.n, p.n) + r.offset * cross(p.n, q.n)) * (1.0 / triple);
  return true;
}

/// Solves min |x - g|^2 subject to n_i . x >= c_i for the `count` planes: every subset of at most
/// three planes taken as equalities, the feasible projection nearest g wins (a feasible point is
/// never nearer g than the optimum, which is the projection onto its own active set). Keeps only
/// the chosen subset in `planes`. Returns false when no candidate is feasible (planes facing each
/// other closer than twice the margin).
bool solve_constraints(const Vec3& g, Plane* planes, std::uint32_t& count, Vec3& x_out) {
  double best = 0.0;
  bool found = false;
  std::uint32_t best_subset[3] = {0, 0, 0};
  std::uint32_t best_size = 0;
  // Bit masks over at most four planes; sizes 0..3.
  const std::uint32_t masks = 1u << count;
  for (std::uint32_t mask = 0; mask < masks; ++mask) {
    std::uint32_t subset[4];
    std::uint32_t size = 0;
    for (std::uint32_t i = 0; i < count; ++i) {
      if (mask & (1u << i)) subset[size++] = i;
    }
    if (size > 3) continue;
    Vec3 x;
    if (!project(g, planes, subset, size, x)) continue;
    bool feasible = is_finite(x);
    for (std::uint32_t i = 0; i < count && feasible; ++i) {
      feasible = dot(planes[i].n, x) >= planes[i].offset - kFeasibilityTolerance;
    }
    if (!feasible) continue;
    const Vec3 d = x - g;
    const double distance2 = dot(d, d);
    if (!found || distance2 < best) {
      found = true;
      best = distance2;
      best_size = size;
      std::copy(subset, subset + size, best_subset);
      x_out = x;
    }
  }
  if (!found) return false;
  Plane kept[3];
  for (std::uint32_t i = 0; i < best_size; ++i) kept[i] = planes[best_subset[i]];
  std::copy(kept, kept + best_size, planes);
  count = best_size;
  return true;
}

/// The point of the segment from -> to (which crosses a plane at signed distances d_from > 0,
/// d_to <= 0 of its end points) that lies `margin` off the plane; `from` itself when it is
/// already that close.
Vec3 stop_before(const Vec3& from, const Vec3& to, double d_from, double d_to, double margin) {
  if (!(d_from > margin)) return from;
  const double s = (d_from - margin) / (d_from - d_to);
  return from + std::clamp(s, 0.0, 1.0) * (to - from);
}

/// Orients a hit triangle's plane toward the side `from` is on (against the motion when `from`
/// lies exactly on it) and returns the signed distances of both end points on that side.
Plane oriented_plane(const SegmentHitResult& hit, const Vec3& from, const Vec3& to,
                     double& d_from, double& d_to) {
  const double s_from = dot(hit.normal_O, from) - hit.plane_offset;
  const double s_to = dot(hit.normal_O, to) - hit.plane_offset;
  const double sign = s_from > 0.0 ? 1.0 : (s_from < 0.0 ? -1.0 : (s_to > 0.0 ? -1.0 : 1.0));
  d_from = sign * s_from;
  d_to = sign * s_to;
  return {sign * hit.normal_O, sign * hit.plane_offset};
}

}  // namespace

void reset_god_object(GodObjectState& state, const MeshPose& pose, const Vec3& p_WT) {
  state.p_OP = to_object(pose, p_WT);
  state.p_WP = p_WT;
  state.n_W = {};
  state.in_contact = false;
  state.initialized = true;
}

GodObjectOutput update_god_object(GodObjectState& state, const MeshBvh& mesh,
                                  const MeshPose& pose, const GodObjectParams& params,
                                  const Vec3& p_WT, const Vec3& v_WT) {
  GodObjectOutput out;
  if (!is_finite(p_WT) || !is_finite(v_WT) || !is_finite(pose.p_WO) || !finite(pose.R_WO) ||
      !is_finite(pose.v_WO) || !is_finite(pose.w_WO)) {
    out.input_rejected = true;
    out.p_WP = state.p_WP;
    out.in_contact = state.in_contact;
    return out;
  }
  if (!state.initialized) reset_god_object(state, pose, p_WT);

  const Vec3 g = to_object(pose, p_WT);  // The goal: the tool in O.
  const double margin = params.margin;
  Vec3 proxy = state.p_OP;
  // The per-tick working set: fixed arrays only (no allocation on this path).
  Plane planes[kGodObjectMaxPlanes];
  std::uint32_t count = 0;
  std::uint32_t iterations = 0;
  while (iterations < kGodObjectMaxIterations) {
    Vec3 target = g;
    if (count > 0) {
      if (!solve_constraints(g, planes, count, target)) break;
      const Vec3 step = target - proxy;
      if (dot(step, step) <= kConvergedDistance * kConvergedDistance) break;
    } else if (proxy == g) {
      break;
    }
    ++iterations;
    const SegmentHitResult hit = mesh.first_hit(proxy, target);
    if (!hit.hit) {
      proxy = target;
      if (count == 0) break;  // Reached the tool.
      count = 0;              // Trace for the tool again from here (see the file comment).
      continue;
    }
    double d_from = 0.0;
    double d_to = 0.0;
    const Plane plane = oriented_plane(hit, proxy, target, d_from, d_to);
    proxy = stop_before(proxy, target, d_from, d_to, margin);
    const Plane constraint{plane.n, plane.offset + margin};
    bool known = false;
    for (std::uint32_t i = 0; i < count; ++i) {
      known = known || (dot(planes[i].n, constraint.n) > 1.0 - 1e-12 &&
                        std::abs(planes[i].offset - constraint.offset) < kFeasibilityTolerance);
    }
    if (known) break;  // Rounding made us cross a plane we already hold: stay here.
    planes[count++] = constraint;  // count <= 3 before this, so <= 4 now.
  }

  state.p_OP = proxy;
  state.in_contact = !(proxy == g);
  out.iterations = iterations;
  out.in_contact = state.in_contact;
  if (!state.in_contact) {
    state.p_WP = p_WT;
    state.n_W = {};
    out.p_WP = p_WT;
    return out;
  }
  const Vec3 p_WP = to_world(pose, proxy);
  const Vec3 spring = p_WP - p_WT;
  const double d = norm(spring);
  state.p_WP = p_WP;
  out.p_WP = p_WP;
  // Report only the constraints the proxy is held by (the QP's active set at its position).
  for (std::uint32_t i = 0; i < count && out.plane_count < 3; ++i) {
    if (dot(planes[i].n, proxy) <= planes[i].offset + kFeasibilityTolerance + 1e-9) {
      out.normals_W[out.plane_count++] = rotate(pose.R_WO, planes[i].n);
    }
  }
  if (!(d > 0.0)) {
    state.n_W = {};
    return out;
  }
  const Vec3 u = spring * (1.0 / d);
  const Vec3 v_surface = pose.v_WO + cross(pose.w_WO, p_WP - pose.p_WO);
  const double v_n = dot(u, v_WT - v_surface);
  const double magnitude = std::max(0.0, params.stiffness * d - params.damping * v_n);
  state.n_W = u;
  out.F_T_W = magnitude * u;
  if (!is_finite(out.F_T_W)) {  // Only with invalid parameters; never hand on a NaN.
    out.F_T_W = {};
    out.input_rejected = true;
  }
  return out;
}

void rebase_god_object(GodObjectState& state, const MeshBvh& new_mesh, const MeshPose& new_pose,
                       const GodObjectParams& params) {
  if (!state.initialized || !is_finite(new_pose.p_WO) || !finite(new_pose.R_WO)) return;
  const Vec3 p_OP = to_object(new_pose, state.p_WP);
  if (!state.in_contact || !(norm(state.n_W) > 0.0)) {
    state.p_OP = p_OP;
    return;
  }
  const Vec3 n_O = rotate(conjugate(new_pose.R_WO), state.n_W);
  const Vec3 start = p_OP + params.replace_lift * n_O;
  const SegmentHitResult hit = new_mesh.first_hit(start, p_OP);
  if (!hit.hit) {
    state.p_OP = p_OP;
    return;
  }
  double d_from = 0.0;
  double d_to = 0.0;
  oriented_plane(hit, start, p_OP, d_from, d_to);
  state.p_OP = stop_before(start, p_OP, d_from, d_to, params.margin);
}

std::string validate_god_object_params(const GodObjectParams& params) {
  char buffer[128];
  auto bad = [&](const char* name, double value, const char* rule) {
    std::snprintf(buffer, sizeof buffer, "%s: %g (%s)", name, value, rule);
    return std::string(buffer);
  };
  if (!std::isfinite(params.stiffness) || params.stiffness < 0.0) {
    return bad("stiffness", params.stiffness, "must be finite and >= 0 N/m");
  }
  if (!std::isfinite(params.damping) || params.damping < 0.0) {
    return bad("damping", params.damping, "must be finite and >= 0 N*s/m");
  }
  if (!std::isfinite(params.margin) || !(params.margin > 0.0) || params.margin > 1e-3) {
    return bad("margin", params.margin, "must be in (0, 1e-3] m");
  }
  if (!std::isfinite(params.replace_lift) || params.replace_lift < 0.0) {
    return bad("replace_lift", params.replace_lift, "must be finite and >= 0 m");
  }
  return "";
}

}  // namespace haptic::engine
