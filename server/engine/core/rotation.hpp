#pragma once
// Rotations as unit quaternions (w, x, y, z) and rotation vectors (axis × angle, rad), for the
// tool's orientation R_WT and orientation fields. Hamilton's convention: q ⊗ p applies p first;
// rotate(q, v) = q v q*. Frames per docs/architecture.md.
//
// Everything here is constexpr or inline, allocates nothing and never throws: it runs per tick.

#include <cmath>

#include "engine/core/vec3.hpp"

namespace haptic::engine {

/// The Hamilton product a ⊗ b: the rotation b, then a.
constexpr Quat operator*(const Quat& a, const Quat& b) {
  return {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
          a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
          a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
          a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}

/// q* = (w, −x, −y, −z); for a unit quaternion, the inverse rotation.
constexpr Quat conjugate(const Quat& q) { return {q.w, -q.x, -q.y, -q.z}; }

/// Euclidean norm of the four components.
inline double norm(const Quat& q) { return std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z); }

inline bool is_finite(const Quat& q) {
  return std::isfinite(q.w) && std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z);
}

/// True when every component is finite and | |q| − 1 | <= tol. The server rejects a pose whose
/// quaternion fails this rather than normalising it silently.
inline bool is_unit(const Quat& q, double tol = 1e-6) {
  return is_finite(q) && std::fabs(norm(q) - 1.0) <= tol;
}

/// q / |q|; the identity when |q| is zero or not finite (so the result is always a rotation).
inline Quat normalized(const Quat& q) {
  const double n = norm(q);
  if (!(n > 0.0) || !std::isfinite(n)) return {};
  return {q.w / n, q.x / n, q.y / n, q.z / n};
}

/// Rᵀ v for the rotation R of the unit quaternion q: the inverse of rotate(q, v).
constexpr Vec3 rotate_inverse(const Quat& q, const Vec3& v) { return rotate(conjugate(q), v); }

/// The rotation by angle_rad (unit: rad, right-handed) about axis (any length; normalised
/// here). A zero or non-finite axis, or a non-finite angle, gives the identity.
inline Quat quat_from_axis_angle(const Vec3& axis, double angle_rad) {
  const double n = norm(axis);
  if (!(n > 0.0) || !std::isfinite(n) || !std::isfinite(angle_rad)) return Quat{};
  // q = (cos θ/2, sin θ/2 â): the rotation by θ about â (Rodrigues; Shoemake 1985).
  const double s = std::sin(0.5 * angle_rad) / n;
  return {std::cos(0.5 * angle_rad), s * axis.x, s * axis.y, s * axis.z};
}

/// The rotation by |r| radians about r/|r| (the exponential map). Exact for every r; the series
/// sin(a)/a ≈ 1 − a²/6 below a = 1e-4 keeps it smooth at zero.
inline Quat rotation_from_vector(const Vec3& r) {
  const double angle = norm(r);
  const double half = 0.5 * angle;
  const double s = angle < 1e-4 ? 0.5 - angle * angle / 48.0 : std::sin(half) / angle;
  return {std::cos(half), s * r.x, s * r.y, s * r.z};
}

/// The rotation vector θ of q (the logarithm map), |θ| ∈ [0, π]: q and −q give the same θ (the
/// shorter way round). Unit: rad. At exactly π the axis's sign is q's.
inline Vec3 rotation_vector(const Quat& q) {
  const double sign = q.w < 0.0 ? -1.0 : 1.0;
  const Vec3 v{sign * q.x, sign * q.y, sign * q.z};
  const double s = norm(v);
  const double w = sign * q.w;
  if (s < 1e-8) return (2.0 / (w > 0.0 ? w : 1.0)) * v;  // θ ≈ 2 v near identity
  const double angle = 2.0 * std::atan2(s, w);
  return (angle / s) * v;
}

/// The rotation from `target` to `orientation`, expressed in W: θ = log(R_WT R_WG⁻¹), so that
/// R_WT = exp(θ) R_WG. Unit: rad. For a spring with U = ½ k |θ|², the torque −k θ is exactly −∇U
/// (θ is an eigenvector, eigenvalue 1, of the left Jacobian's inverse), so the spring is
/// conservative at every angle below π.
inline Vec3 orientation_error_W(const Quat& R_WT, const Quat& R_WG) {
  return rotation_vector(R_WT * conjugate(R_WG));
}

}  // namespace haptic::engine
