#pragma once
// Convex primitive shapes of the scene, their signed-distance queries and their world bounds.
//
// Each shape is described in its object frame O and placed in W by a pose (p_WO, R_WO). A query
// of a point Q returns the signed distance to the surface (negative inside), the closest surface
// point S and the outward unit normal at S. Queries are exact (not bounds) for every shape here,
// inside and outside, return finite values for every finite input (degenerate points pick a
// fixed direction, documented per shape) and never allocate: they may run on the loop.
// Validation (validate*, is_unit) runs at the boundary, off the loop.

#include <cmath>
#include <optional>
#include <string>
#include <variant>

#include "engine/core/rotation.hpp"
#include "engine/core/vec3.hpp"
#include "engine/scene/scene_spec.hpp"

namespace haptic::engine {

// ---------------------------------------------------------------------------------------------
// Shapes. HalfSpaceSpec and SphereSpec are the scene's own (scene_spec.hpp):
//   HalfSpaceSpec: the surface passes through the object origin with outward normal normal_O.
//   SphereSpec:    a solid sphere of the given radius centred on the object origin.

// BoxSpec and CapsuleSpec are in scene_spec.hpp too.

/// Any primitive; what a contact proxy or a scene compiler holds per object.
using PrimitiveShape = std::variant<HalfSpaceSpec, SphereSpec, BoxSpec, CapsuleSpec>;

/// Where an object sits: its frame O in W.
struct ObjectPose {
  Vec3 p_WO;  // Origin of O in W. Unit: m.
  Quat R_WO;  // Orientation of O in W; unit (is_unit) by validation.
};

/// p_WQ for a point given in O: p_WO + R_WO p_OQ.
constexpr Vec3 to_world(const ObjectPose& X_WO, const Vec3& p_OQ) {
  return X_WO.p_WO + rotate(X_WO.R_WO, p_OQ);
}
/// p_OQ for a point given in W: R_WOᵀ (p_WQ − p_WO).
constexpr Vec3 to_object(const ObjectPose& X_WO, const Vec3& p_WQ) {
  return rotate_inverse(X_WO.R_WO, p_WQ - X_WO.p_WO);
}

/// Result of a query in W. S is the surface point closest to the query point Q.
struct ShapeQuery {
  double signed_distance = 0.0;  // |p_WQ − p_WS|, negative when Q is inside. Unit: m.
  Vec3 p_WS;                     // Closest surface point, in W. Unit: m.
  Vec3 n_W;                      // Outward unit normal at S, in W. The gradient of the distance.
};

/// The same in the object frame O.
struct LocalShapeQuery {
  double signed_distance = 0.0;  // Unit: m; negative inside.
  Vec3 p_OS;                     // Closest surface point, in O. Unit: m.
  Vec3 n_O;                      // Outward unit normal at S, in O.
};

/// Half-space: signed distance dot(p_OQ, n̂), S = Q − d n̂, n̂ = normal_O / |normal_O| (a zero or
/// non-finite normal_O, which validation rejects, is taken as +z).
LocalShapeQuery query_local(const HalfSpaceSpec& shape, const Vec3& p_OQ);
/// Sphere: d = |p_OQ| − r along the radial direction; at the centre the normal is O's +z.
LocalShapeQuery query_local(const SphereSpec& shape, const Vec3& p_OQ);
/// Box. Outside (some |q_i| > h_i): S = clamp(q, −h, h), the nearest point of a face, edge or
/// corner, n = (q − S)/|q − S|. Inside or on the surface: the nearest face, i.e. the axis i with
/// the smallest depth h_i − |q_i|; ties (edges, corners, the centre of a cube) go to the lowest
/// axis (x before y before z), and q_i = 0 to the + face. d = |q_i| − h_i, n = ±e_i.
LocalShapeQuery query_local(const BoxSpec& shape, const Vec3& p_OQ);
/// Capsule: the distance to the axis segment minus the radius, measured from the segment point
/// nearest Q (z clamped to ±half_length). On the axis segment itself the normal is O's +x.
LocalShapeQuery query_local(const CapsuleSpec& shape, const Vec3& p_OQ);
LocalShapeQuery query_local(const PrimitiveShape& shape, const Vec3& p_OQ);

/// The query of point p_WQ against a shape placed at X_WO. Rotates into O, queries, and rotates
/// the point and normal back; the distance is frame-independent.
template <typename Shape>
ShapeQuery query(const Shape& shape, const ObjectPose& X_WO, const Vec3& p_WQ) {
  const LocalShapeQuery local = query_local(shape, to_object(X_WO, p_WQ));
  return {local.signed_distance, to_world(X_WO, local.p_OS), rotate(X_WO.R_WO, local.n_O)};
}

/// Axis-aligned bounding box in W, for the broad phase. Unit: m.
struct ShapeBounds {
  Vec3 min_W;
  Vec3 max_W;
};

/// True when p_W lies in the box grown by margin (unit: m) on every side.
constexpr bool contains(const ShapeBounds& b, const Vec3& p_W, double margin = 0.0) {
  return p_W.x >= b.min_W.x - margin && p_W.x <= b.max_W.x + margin &&
         p_W.y >= b.min_W.y - margin && p_W.y <= b.max_W.y + margin &&
         p_W.z >= b.min_W.z - margin && p_W.z <= b.max_W.z + margin;
}

/// Tight world bounds of a placed shape: centre ± r for a sphere; for a box the extent along W's
/// axis i is Σ_j |R_ij| h_j (the rotated box's support, Ericson 2005, "Real-Time Collision
/// Detection" §4.2.6); for a capsule the rotated segment's bounds grown by the radius. A
/// half-space is unbounded and has no bounds: it cannot go in a broad phase and must be tested
/// against every tool point (bounds() of a PrimitiveShape returns nullopt for it).
ShapeBounds bounds(const SphereSpec& shape, const ObjectPose& X_WO);
ShapeBounds bounds(const BoxSpec& shape, const ObjectPose& X_WO);
ShapeBounds bounds(const CapsuleSpec& shape, const ObjectPose& X_WO);
std::optional<ShapeBounds> bounds(const PrimitiveShape& shape, const ObjectPose& X_WO);

/// Validation at the boundary: "" when usable, else one message naming the first bad field and
/// its value ("half_extents.y: must be finite and > 0, got 0"). The caller prefixes the
/// object's path ("objects[3].box."). Never throws.
std::string validate(const HalfSpaceSpec& shape);
std::string validate(const SphereSpec& shape);
std::string validate(const BoxSpec& shape);
std::string validate(const CapsuleSpec& shape);
std::string validate(const PrimitiveShape& shape);
/// p_WO finite and R_WO unit within 1e-6 (is_unit); names "p_WO.x" … or "R_WO".
std::string validate(const ObjectPose& X_WO);

}  // namespace haptic::engine
