#include "engine/scene/contact_proxy.hpp"
#include "engine/core/parameter_checks.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace haptic::engine {
namespace {

bool non_negative(double v) { return std::isfinite(v) && v >= 0.0; }

}  // namespace

std::string validate(const ContactMaterial& m) {
  if (!non_negative(m.stiffness)) return bad_parameter("stiffness", "must be finite and >= 0", m.stiffness);
  if (!non_negative(m.damping)) return bad_parameter("damping", "must be finite and >= 0", m.damping);
  if (!non_negative(m.static_friction)) {
    return bad_parameter("static_friction", "must be finite and >= 0", m.static_friction);
  }
  if (!non_negative(m.dynamic_friction) || m.dynamic_friction > m.static_friction) {
    std::ostringstream requirement;
    requirement << "must be finite, >= 0 and <= static_friction (" << m.static_friction << ")";
    return bad_parameter("dynamic_friction", requirement.str().c_str(), m.dynamic_friction);
  }
  return {};
}

ContactForce no_contact(const Vec3& p_WT) {
  ContactForce out;
  out.p_WP = p_WT;
  return out;
}

ContactForce contact_force(const LocalShapeQuery& query_at_tool, const ObjectPose& X_WO,
                           const ContactMaterial& material, const Vec3& p_OP, const Vec3& v_WT) {
  ContactForce out;
  out.in_contact = true;
  out.penetration = -query_at_tool.signed_distance;
  out.n_W = rotate(X_WO.R_WO, query_at_tool.n_O);
  out.p_WP = to_world(X_WO, p_OP);
  // Normal part of eq. (1): K d − B v·n̂, clamped at zero so the surface never pulls (a damper
  // that pulled would hold the tool inside while it leaves; as in evaluate_scene.cpp).
  const double normal =
      std::max(0.0, material.stiffness * out.penetration - material.damping * dot(v_WT, out.n_W));
  out.F_T_W = normal * out.n_W;
  // Tangential part: K (p_P − p_S), zero for the penalty law (p_OP = p_OS).
  const Vec3 t_O = p_OP - query_at_tool.p_OS;
  if (!(t_O == Vec3{})) out.F_T_W += material.stiffness * rotate(X_WO.R_WO, t_O);
  return out;
}

Vec3 ContactProxy::friction_step(const LocalShapeQuery& at_tool, const ContactMaterial& material) {
  const double depth = -at_tool.signed_distance;
  const Vec3 t = p_OP_ - at_tool.p_OS;  // Tangential offset; |K t| is the friction force.
  const double t_length = norm(t);
  // Static cone while sticking, dynamic cone while sliding (Salisbury et al. 1995, §4).
  const double cone = (sliding_ ? material.dynamic_friction : material.static_friction) * depth;
  if (t_length <= cone) {
    sliding_ = false;
    return p_OP_;
  }
  sliding_ = true;
  // Onto the dynamic cone's edge: |t'| = μ_d d along the same direction (t_length > 0 here).
  const double scale = material.dynamic_friction * depth / t_length;
  return at_tool.p_OS + scale * t;
}

}  // namespace haptic::engine
