#pragma once
// The scene as clients describe it, after validation at the boundary (server/net): objects and
// fields in engine types. Engine code assumes these are valid (finite, in range).

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <variant>
#include <vector>

#include "engine/core/site_key.hpp"
#include "engine/core/vec3.hpp"
#include "engine/scene/fields.hpp"
#include "engine/scene/mesh.hpp"
#include "engine/scene/orientation_fields.hpp"

namespace haptic::engine {

/// Half-space wall: the surface passes through the object origin with outward normal normal_O
/// (object frame); the solid is on the other side.
struct HalfSpaceSpec {
  Vec3 normal_O{0.0, 0.0, 1.0};  // Non-zero; normalised at compile time.
};

/// Solid sphere centred on the object origin.
struct SphereSpec {
  double radius = 0.0;  // Unit: m. > 0.
};

/// Solid box centred on the object origin, its faces normal to O's axes.
struct BoxSpec {
  Vec3 half_extents;  // Half the side lengths along O's x, y, z. Unit: m. Each > 0.
};

/// Solid capsule: the points within `radius` of the segment from (0, 0, −half_length) to
/// (0, 0, +half_length) in O (a cylinder along O's z axis with hemispherical caps).
struct CapsuleSpec {
  double radius = 0.0;       // Unit: m. > 0.
  double half_length = 0.0;  // Half the length of the axis segment. Unit: m. >= 0 (0: a sphere).
};

/// Russo's tangent-plane local model (1990, ch. 5): the plane through the object origin with
/// outward normal normal_O that a slow host sends for the surface nearest the tool, with a
/// tangential spring-damper about a surface reference point (the normal law is the object's
/// impedance). Acts only while the tool is behind the plane. Frame O.
struct TangentPlaneSpec {
  Vec3 normal_O{0.0, 0.0, 1.0};  // Non-zero; normalised at compile time.
  Vec3 reference_O;              // The tangential spring's rest point. Unit: m.
  double tangential_stiffness = 0.0;  // K_t. Unit: N/m.
  double tangential_damping = 0.0;    // b_t. Unit: N·s/m.
};

/// A validated triangle mesh and its bounding-volume hierarchy, built once off the loop and
/// shared (never copied) by every snapshot that holds the object.
struct MeshModel {
  Mesh mesh;
  MeshBvh bvh;
};

/// A triangle mesh in O, rendered with a god object (engine/scene/god_object).
struct MeshShapeSpec {
  std::shared_ptr<const MeshModel> model;
};

struct ObjectSpec {
  Vec3 p_WO;           // Object origin in W. Unit: m.
  Quat R_WO;           // Object orientation in W (unit quaternion).
  double stiffness = 0.0;  // Unit: N/m.
  double damping = 0.0;    // Unit: N*s/m.
  double impedance_mass = 0.0;    // M of the discrete laws. Unit: kg.
  double static_friction = 0.0;   // μ_s (needs the kVelocity law).
  double dynamic_friction = 0.0;  // μ_d ≤ μ_s.
  ContactLaw law = ContactLaw::kVelocity;
  std::variant<HalfSpaceSpec, SphereSpec, BoxSpec, CapsuleSpec, MeshShapeSpec, TangentPlaneSpec> shape;
  /// A virtual mass the tool can push (000 eq. 7.1, f_V = m_V Ẍ + B_V Ẋ): the object translates
  /// under the reaction of its contact force. 0: fixed. Unit: kg.
  double object_mass = 0.0;
  double object_damping = 0.0;  // B_V, its viscous friction with the ground. Unit: N·s/m.
  /// Sharing rule: any session may update a shared object (move it, change its impedance); only
  /// its owner may delete it, and it goes when the owner's session does. Not shared: only the
  /// owner changes it. Every tool feels every object either way.
  bool shared = false;
  /// A virtual mass shared across the sites of a federation (docs/federation.md, "Shared
  /// masses"): each site's copy is coupled to the others'. Its key at every site: the site that
  /// made it (origin_site; none: this site) and its id there (origin_id; 0: this item's own id).
  bool across_sites = false;
  SiteKey origin_site;
  std::uint64_t origin_id = 0;
};

/// Potential U = 1/2 k |p - anchor|^2; F = -k (p - anchor) - b v, clipped to max_force if > 0.
struct SpringToPointSpec {
  Vec3 anchor_W;           // Unit: m.
  double stiffness = 0.0;  // Unit: N/m.
  double damping = 0.0;    // Unit: N*s/m.
  double max_force = 0.0;  // Unit: N. 0: no clip.
};

struct FieldSpec {
  std::variant<SpringToPointSpec, PotentialFieldSpec, SpringFieldSpec, LinearFieldSpec,
               ViscousFieldSpec, DetentFieldSpec, OrientationSpringSpec, OrientationDetentSpec>
      kind;
};

inline constexpr std::int64_t kNeverTick = std::numeric_limits<std::int64_t>::max();
/// appear_tick of an item that was always there (no fade-in).
inline constexpr std::int64_t kAlwaysTick = std::numeric_limits<std::int64_t>::min();

/// When an item's force ramps in and out, so that no appearance, change or removal steps the
/// force. With R the ramp length in ticks and ramp(x) = clamp(x / R, 0, 1), an item contributes with
///   gain = in · out · Π_j out_j,   in = ramp(tick − appear_tick) (1 if it was always there),
///   out = 1 − ramp(tick − fade_begin_tick) (removal), out_j = 1 − ramp(tick − superseded_at[j]).
/// An update keeps the item's id and adds a version: the new one fades in from its appear tick and
/// every older version of the item gets that tick in superseded_at. For versions v_1 (oldest) …
/// v_n the gains are in_k Π_{j>k} (1 − in_j), which sum to 1 at every tick (a telescoping product),
/// so a change cross-fades the force however fast updates come, up to kMaxVersions in flight.
struct ItemRamp {
  static constexpr std::size_t kMaxSuperseded = 3;  // so at most four versions of one item
  std::int64_t appear_tick = kAlwaysTick;
  std::int64_t fade_begin_tick = kNeverTick;
  std::array<std::int64_t, kMaxSuperseded> superseded_at{kNeverTick, kNeverTick, kNeverTick};
};

/// Who owns an item, and how its force ramps.
struct ItemMeta {
  std::uint64_t session_id = 0;  // 0: owned by the server itself.
  std::uint64_t id = 0;          // Unique across all sessions; kept by updates.
  std::int64_t fade_begin_tick = kNeverTick;
  ItemRamp ramps;                // appear and superseded ticks (fade_begin_tick above is the removal)
  /// Unique per version of an item: the key its loop state is carried by. 0: the item's id.
  std::uint64_t version_key = 0;

  std::uint64_t state_key() const { return version_key != 0 ? version_key : id; }

  ItemRamp ramp() const {
    ItemRamp out = ramps;
    out.fade_begin_tick = fade_begin_tick;
    return out;
  }
};

struct ObjectEntry {
  ItemMeta meta;
  ObjectSpec spec;
};

struct FieldEntry {
  ItemMeta meta;
  FieldSpec spec;
};

/// Everything in the shared scene, across sessions.
struct SceneDescription {
  std::vector<ObjectEntry> objects;
  std::vector<FieldEntry> fields;
};

}  // namespace haptic::engine
