#pragma once
// Contact with one convex primitive: the frictionless penalty law, and a friction proxy.
//
// The friction proxy is the friction-cone god-object of Salisbury et al. 1995 ("Haptic
// rendering: programming touch interaction with virtual objects", §4, static and dynamic
// friction) and Ruspini, Kolarov and Khatib 1997 ("The haptic display of complex graphical
// environments", §5, the proxy moves only when the tool leaves the friction cone). While the
// tool T is inside the shape, the proxy P stays on the surface and the force is the spring
//   F_T_W = K (p_WP − p_WT) − B (v_WT · n̂) n̂                                           (1)
// with the normal part clamped so the surface only pushes. Write S for the surface point closest
// to T, d = |p_WS − p_WT| for the penetration and t = p_WP − p_WS, so that (1) splits into a
// normal force K d (+ damping) along n̂ and a tangential force K t. Coulomb's law with μ_s ≥ μ_d:
//   sticking: P stays where it is while |K t| <= μ_s K d (inside the static cone);
//   breaking away or sliding: P moves along the surface towards S until |K t| = μ_d K d, and
//     keeps sliding each tick while the tool pulls it past the dynamic cone; once the tool is
//     back inside the dynamic cone (|t| <= μ_d d) P sticks again and μ_s applies anew.
// On a flat face t lies in the tangent plane and these are exact Coulomb forces; on a curved
// surface t is a chord and the slid proxy is projected back onto the surface.
//
// P is stored in the object frame O, so a moving object carries a sticking proxy along; the state
// resets when the tool leaves the shape. With μ_s = μ_d = 0 the proxy is always S and (1) is the
// penalty law of penalty_contact() exactly (bit for bit), so a scene compiler may skip the proxy
// and its state for frictionless materials.
//
// Choices to know: damping acts along the normal only (a tangential damper would be viscous
// friction even at μ = 0, and would break the reduction to the penalty law), and the friction
// cone is tested against the spring part K d of the normal force, as in the geometric cone of
// the papers above. A new contact starts with P at S (no tangential force on its first tick).
// For deep penetration of a box near an edge, S may jump to the neighbouring face; meshes and
// thin parts need the constrained god-object, not this per-primitive proxy.
//
// Nothing here allocates; update() and penalty_contact() may run on the loop.

#include <string>

#include "engine/core/vec3.hpp"
#include "engine/scene/shapes.hpp"

namespace haptic::engine {

/// The contact part of an object's material.
struct ContactMaterial {
  double stiffness = 0.0;         // K. Unit: N/m. Finite, >= 0.
  double damping = 0.0;           // B, along the normal. Unit: N·s/m. Finite, >= 0.
  double static_friction = 0.0;   // μ_s. Dimensionless. Finite, >= 0.
  double dynamic_friction = 0.0;  // μ_d. Dimensionless. Finite, 0 <= μ_d <= μ_s.
};

/// "" when usable, else one message naming the first bad field and its value
/// ("dynamic_friction: must be finite, >= 0 and <= static_friction (0.4), got 0.6").
std::string validate(const ContactMaterial& material);

/// True when the material has no friction (μ_s = 0, hence μ_d = 0 when valid): contact is then
/// penalty_contact() and needs no ContactProxy state.
constexpr bool is_frictionless(const ContactMaterial& m) {
  return m.static_friction == 0.0 && m.dynamic_friction == 0.0;
}

/// The contact at one tick.
struct ContactForce {
  Vec3 F_T_W;                 // Force on the tool, in W. Unit: N. Zero out of contact.
  Vec3 p_WP;                  // Proxy point in W (on the surface); p_WT out of contact. Unit: m.
  Vec3 n_W;                   // Outward unit normal at S, in W; zero out of contact.
  double penetration = 0.0;   // d = −(signed distance of T). Unit: m. > 0 in contact, else 0.
  bool in_contact = false;    // T strictly inside the shape.
  bool sliding = false;       // The proxy moved along the surface this tick (kinetic friction).
};

/// Assembles (1) from the query at the tool (in O) and the proxy's offset t_O = p_OP − p_OS.
/// Shared by penalty_contact() and ContactProxy so their frictionless results are identical.
/// query_at_tool must be a contact (signed_distance < 0).
ContactForce contact_force(const LocalShapeQuery& query_at_tool, const ObjectPose& X_WO,
                           const ContactMaterial& material, const Vec3& p_OP, const Vec3& v_WT);

/// The result out of contact: zero force, proxy at the tool.
ContactForce no_contact(const Vec3& p_WT);

/// Frictionless contact, stateless: F = max(0, K d − B (v_WT · n̂)) n̂ with n̂ the outward normal
/// at the surface point S closest to T (the law of evaluate_scene.cpp for walls and spheres).
/// v_WT is the tool's velocity relative to the object (for a moving object, subtract the
/// object's velocity at S). Unit: m/s. Uses only stiffness and damping of the material.
template <typename Shape>
ContactForce penalty_contact(const Shape& shape, const ObjectPose& X_WO,
                             const ContactMaterial& material, const Vec3& p_WT, const Vec3& v_WT) {
  const LocalShapeQuery at_tool = query_local(shape, to_object(X_WO, p_WT));
  if (!(at_tool.signed_distance < 0.0)) return no_contact(p_WT);
  return contact_force(at_tool, X_WO, material, at_tool.p_OS, v_WT);
}

/// Per-(tool, object) contact state: the friction proxy described above. Default-constructed out
/// of contact. Holds no references; the shape, pose and material are passed each tick, so the
/// object may move or be replaced between ticks (the stored proxy is projected onto the current
/// surface before it is used).
class ContactProxy {
 public:
  /// Advances the proxy to the tool position p_WT (unit: m) and returns the contact force.
  /// v_WT: the tool's velocity relative to the object (unit: m/s), for the normal damping.
  /// Shape: HalfSpaceSpec, SphereSpec, BoxSpec, CapsuleSpec or PrimitiveShape. Pose and material
  /// valid (validate()). Does not allocate.
  template <typename Shape>
  ContactForce update(const Shape& shape, const ObjectPose& X_WO, const ContactMaterial& material,
                      const Vec3& p_WT, const Vec3& v_WT) {
    const LocalShapeQuery at_tool = query_local(shape, to_object(X_WO, p_WT));
    if (!(at_tool.signed_distance < 0.0)) {
      reset();
      return no_contact(p_WT);
    }
    if (!in_contact_ || is_frictionless(material)) {
      p_OP_ = at_tool.p_OS;
      sliding_ = false;
    } else {
      p_OP_ = query_local(shape, p_OP_).p_OS;
      const Vec3 slid = friction_step(at_tool, material);
      if (sliding_) p_OP_ = query_local(shape, slid).p_OS;
    }
    in_contact_ = true;
    ContactForce out = contact_force(at_tool, X_WO, material, p_OP_, v_WT);
    out.sliding = sliding_;
    return out;
  }

  /// Forgets the contact (the next update() in contact starts a new one).
  void reset() {
    in_contact_ = false;
    sliding_ = false;
    p_OP_ = {};
  }

  bool in_contact() const { return in_contact_; }
  /// True while the proxy is sliding (dynamic friction applies), false while it sticks.
  bool sliding() const { return sliding_; }
  /// The proxy in the object frame O. Unit: m. Meaningful only while in_contact().
  const Vec3& p_OP() const { return p_OP_; }

 private:
  /// The stick/slip decision on the current (surface) proxy p_OP_: updates sliding_ and returns
  /// the slid proxy (before projection onto a curved surface) when sliding, else p_OP_.
  Vec3 friction_step(const LocalShapeQuery& at_tool, const ContactMaterial& material);

  Vec3 p_OP_;  // Proxy in O. Unit: m.
  bool in_contact_ = false;
  bool sliding_ = false;
};

}  // namespace haptic::engine
