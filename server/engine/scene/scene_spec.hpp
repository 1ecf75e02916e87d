#pragma once
// The scene as clients describe it, after validation at the boundary (server/net): objects and
// fields in engine types. Engine code assumes these are valid (finite, in range).

#include <cstdint>
#include <limits>
#include <variant>
#include <vector>

#include "engine/core/vec3.hpp"

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

struct ObjectSpec {
  Vec3 p_WO;           // Object origin in W. Unit: m.
  Quat R_WO;           // Object orientation in W (unit quaternion).
  double stiffness = 0.0;  // Unit: N/m.
  double damping = 0.0;    // Unit: N*s/m.
  std::variant<HalfSpaceSpec, SphereSpec> shape;
};

/// Potential U = 1/2 k |p - anchor|^2; F = -k (p - anchor) - b v, clipped to max_force if > 0.
struct SpringToPointSpec {
  Vec3 anchor_W;           // Unit: m.
  double stiffness = 0.0;  // Unit: N/m.
  double damping = 0.0;    // Unit: N*s/m.
  double max_force = 0.0;  // Unit: N. 0: no clip.
};

struct FieldSpec {
  std::variant<SpringToPointSpec> kind;
};

inline constexpr std::int64_t kNeverTick = std::numeric_limits<std::int64_t>::max();

/// Who owns an item, and whether it is fading out. An item whose fade began at tick t0 contributes
/// with gain 1 - (tick - t0) / ramp_ticks, clamped to [0, 1], so removal never steps the force.
struct ItemMeta {
  std::uint64_t session_id = 0;  // 0: owned by the server itself.
  std::uint64_t id = 0;          // Unique across all sessions.
  std::int64_t fade_begin_tick = kNeverTick;
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
