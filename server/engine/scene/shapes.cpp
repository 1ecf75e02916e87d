#include "engine/scene/shapes.hpp"
#include "engine/core/parameter_checks.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace haptic::engine {
namespace {

double component(const Vec3& v, int axis) { return axis == 0 ? v.x : (axis == 1 ? v.y : v.z); }

Vec3 unit_axis(int axis, double sign) {
  Vec3 e;
  if (axis == 0) e.x = sign;
  if (axis == 1) e.y = sign;
  if (axis == 2) e.z = sign;
  return e;
}

Vec3 abs_components(const Vec3& v) { return {std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)}; }

/// v / length with length = |v|, or fallback when v is zero. Below ~1e-150 m the squared norm
/// loses precision and then underflows, so tiny vectors are first scaled by an exact power of
/// two; the result is a unit vector for every finite non-zero v.
Vec3 direction_or(const Vec3& v, double length, const Vec3& fallback) {
  if (length > 1e-150) return {v.x / length, v.y / length, v.z / length};
  if (v == Vec3{}) return fallback;
  const Vec3 scaled = v * 0x1p600;
  const double scaled_length = norm(scaled);
  return {scaled.x / scaled_length, scaled.y / scaled_length, scaled.z / scaled_length};
}

/// The first non-finite component of v, named field.x/.y/.z; "" when all are finite.
std::string non_finite_component(const std::string& field, const Vec3& v) {
  if (!std::isfinite(v.x)) return bad_parameter(field + ".x", "must be finite", v.x);
  if (!std::isfinite(v.y)) return bad_parameter(field + ".y", "must be finite", v.y);
  if (!std::isfinite(v.z)) return bad_parameter(field + ".z", "must be finite", v.z);
  return {};
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Quaternions.

// ---------------------------------------------------------------------------------------------
// Queries in O.

LocalShapeQuery query_local(const HalfSpaceSpec& shape, const Vec3& p_OQ) {
  const double length = norm(shape.normal_O);
  const Vec3 n = (length > 0.0 && std::isfinite(length))
                     ? Vec3{shape.normal_O.x / length, shape.normal_O.y / length,
                            shape.normal_O.z / length}
                     : Vec3{0.0, 0.0, 1.0};
  const double d = dot(p_OQ, n);
  return {d, p_OQ - d * n, n};
}

LocalShapeQuery query_local(const SphereSpec& shape, const Vec3& p_OQ) {
  const double length = norm(p_OQ);
  // Exactly at the centre every direction is nearest: take +z.
  const Vec3 n = direction_or(p_OQ, length, {0.0, 0.0, 1.0});
  return {length - shape.radius, shape.radius * n, n};
}

LocalShapeQuery query_local(const BoxSpec& shape, const Vec3& p_OQ) {
  const Vec3& h = shape.half_extents;
  const Vec3 clamped{std::clamp(p_OQ.x, -h.x, h.x), std::clamp(p_OQ.y, -h.y, h.y),
                     std::clamp(p_OQ.z, -h.z, h.z)};
  const Vec3 offset = p_OQ - clamped;
  if (!(offset == Vec3{})) {  // offset is non-zero here, so direction_or needs no fallback.
    // Outside: the clamped point is the nearest point of the box (a face, edge or corner
    // region; Ericson 2005, §5.1.3), and the distance gradient points from it to Q.
    const double distance = norm(offset);
    return {distance, clamped, direction_or(offset, distance, {})};
  }
  // Inside or on the surface: the face with the smallest depth h_i − |q_i|; strict comparison
  // keeps the lowest axis on ties, so edges and corners resolve x, then y, then z.
  const Vec3 q_abs = abs_components(p_OQ);
  int axis = 0;
  double best = q_abs.x - h.x;
  for (int i = 1; i < 3; ++i) {
    const double d = component(q_abs, i) - component(h, i);
    if (d > best) {
      best = d;
      axis = i;
    }
  }
  const double sign = component(p_OQ, axis) >= 0.0 ? 1.0 : -1.0;
  Vec3 surface = p_OQ;
  const double face = sign * component(h, axis);
  if (axis == 0) surface.x = face;
  if (axis == 1) surface.y = face;
  if (axis == 2) surface.z = face;
  return {best, surface, unit_axis(axis, sign)};
}

LocalShapeQuery query_local(const CapsuleSpec& shape, const Vec3& p_OQ) {
  const Vec3 axis_point{0.0, 0.0, std::clamp(p_OQ.z, -shape.half_length, shape.half_length)};
  const Vec3 radial = p_OQ - axis_point;
  const double length = norm(radial);
  // On the axis segment every radial direction is nearest: take +x.
  const Vec3 n = direction_or(radial, length, {1.0, 0.0, 0.0});
  return {length - shape.radius, axis_point + shape.radius * n, n};
}

LocalShapeQuery query_local(const PrimitiveShape& shape, const Vec3& p_OQ) {
  return std::visit([&](const auto& s) { return query_local(s, p_OQ); }, shape);
}

// ---------------------------------------------------------------------------------------------
// Bounds.

ShapeBounds bounds(const SphereSpec& shape, const ObjectPose& X_WO) {
  const Vec3 r{shape.radius, shape.radius, shape.radius};
  return {X_WO.p_WO - r, X_WO.p_WO + r};
}

ShapeBounds bounds(const BoxSpec& shape, const ObjectPose& X_WO) {
  // Columns of R_WO are O's axes in W; the extent along W's axis i is Σ_j |R_ij| h_j.
  const Vec3 ex = abs_components(rotate(X_WO.R_WO, {shape.half_extents.x, 0.0, 0.0}));
  const Vec3 ey = abs_components(rotate(X_WO.R_WO, {0.0, shape.half_extents.y, 0.0}));
  const Vec3 ez = abs_components(rotate(X_WO.R_WO, {0.0, 0.0, shape.half_extents.z}));
  const Vec3 extent = ex + ey + ez;
  return {X_WO.p_WO - extent, X_WO.p_WO + extent};
}

ShapeBounds bounds(const CapsuleSpec& shape, const ObjectPose& X_WO) {
  const Vec3 half_axis = abs_components(rotate(X_WO.R_WO, {0.0, 0.0, shape.half_length}));
  const Vec3 extent = half_axis + Vec3{shape.radius, shape.radius, shape.radius};
  return {X_WO.p_WO - extent, X_WO.p_WO + extent};
}

std::optional<ShapeBounds> bounds(const PrimitiveShape& shape, const ObjectPose& X_WO) {
  if (std::holds_alternative<HalfSpaceSpec>(shape)) return std::nullopt;
  if (const auto* s = std::get_if<SphereSpec>(&shape)) return bounds(*s, X_WO);
  if (const auto* s = std::get_if<BoxSpec>(&shape)) return bounds(*s, X_WO);
  return bounds(std::get<CapsuleSpec>(shape), X_WO);
}

// ---------------------------------------------------------------------------------------------
// Validation.

std::string validate(const HalfSpaceSpec& shape) {
  if (auto message = non_finite_component("normal_O", shape.normal_O); !message.empty()) {
    return message;
  }
  const double length = norm(shape.normal_O);
  if (!(length > 0.0) || !std::isfinite(length)) {
    return bad_parameter("normal_O", "must be non-zero with a finite length", shape.normal_O);
  }
  return {};
}

std::string validate(const SphereSpec& shape) {
  if (!std::isfinite(shape.radius) || !(shape.radius > 0.0)) {
    return bad_parameter("radius", "must be finite and > 0", shape.radius);
  }
  return {};
}

std::string validate(const BoxSpec& shape) {
  const Vec3& h = shape.half_extents;
  const char* names[3] = {"half_extents.x", "half_extents.y", "half_extents.z"};
  for (int i = 0; i < 3; ++i) {
    const double v = component(h, i);
    if (!std::isfinite(v) || !(v > 0.0)) return bad_parameter(names[i], "must be finite and > 0", v);
  }
  return {};
}

std::string validate(const CapsuleSpec& shape) {
  if (!std::isfinite(shape.radius) || !(shape.radius > 0.0)) {
    return bad_parameter("radius", "must be finite and > 0", shape.radius);
  }
  if (!std::isfinite(shape.half_length) || !(shape.half_length >= 0.0)) {
    return bad_parameter("half_length", "must be finite and >= 0", shape.half_length);
  }
  return {};
}

std::string validate(const PrimitiveShape& shape) {
  return std::visit([](const auto& s) { return validate(s); }, shape);
}

std::string validate(const ObjectPose& X_WO) {
  if (auto message = non_finite_component("p_WO", X_WO.p_WO); !message.empty()) return message;
  if (!is_unit(X_WO.R_WO)) {
    const Quat& q = X_WO.R_WO;
    std::ostringstream out;
    out << "R_WO: must be a finite unit quaternion (| |q| - 1 | <= 1e-6), got (" << q.w << ", "
        << q.x << ", " << q.y << ", " << q.z << ") with |q| = " << norm(q);
    return out.str();
  }
  return {};
}

}  // namespace haptic::engine
