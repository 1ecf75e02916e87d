#pragma once
// The scene compiled for the loop: flat arrays per kind of contribution, world-frame geometry
// precomputed, nothing the scene does not use. Immutable once built; the loop reads it through a
// pointer handed over by runtime/SnapshotExchange and never allocates or frees it.

#include <cstdint>
#include <vector>

#include "engine/core/vec3.hpp"
#include "engine/scene/scene_spec.hpp"

namespace haptic::engine {

struct CompiledHalfSpace {
  Vec3 point_W;       // A point on the surface. Unit: m.
  Vec3 normal_W;      // Unit outward normal.
  double stiffness;   // Unit: N/m.
  double damping;     // Unit: N*s/m.
  ItemRamp ramp;
};

struct CompiledSphere {
  Vec3 center_W;      // Unit: m.
  double radius;      // Unit: m.
  double stiffness;   // Unit: N/m.
  double damping;     // Unit: N*s/m.
  ItemRamp ramp;
};

struct CompiledSpring {
  Vec3 anchor_W;      // Unit: m.
  double stiffness;   // Unit: N/m.
  double damping;     // Unit: N*s/m.
  double max_force;   // Unit: N; 0 = no clip.
  ItemRamp ramp;
};

struct CompiledScene {
  std::vector<CompiledHalfSpace> half_spaces;
  std::vector<CompiledSphere> spheres;
  std::vector<CompiledSpring> springs;
  std::int64_t removal_ramp_ticks = 50;  // Ticks over which a removed item fades out; >= 1.
  std::uint64_t generation = 0;          // Increases with every published scene.
};

/// Flattens a description into a compiled scene (off the loop; allocates).
CompiledScene compile_scene(const SceneDescription& description, std::int64_t removal_ramp_ticks,
                            std::uint64_t generation);

/// What the scene asks of the device at one tick.
struct SceneForce {
  Vec3 F_T_W;                    // Force on the tool, in W. Unit: N.
  Vec3 p_WP;                     // Proxy point: the surface point of the deepest contact, else p_WT.
  std::uint32_t contact_count = 0;
  bool ramping = false;          // Some item is fading out (removed, or an old version of a change).
};

/// Sums every contribution at tool position p_WT and velocity v_WT. Does not allocate.
/// Contact with a half-space: d = dot(point - p, n) > 0 is the penetration, F = (k d - b dot(v, n)) n
/// clamped so a wall only pushes (never pulls). Sphere: the same along the radial direction.
SceneForce evaluate_scene(const CompiledScene& scene, const Vec3& p_WT, const Vec3& v_WT,
                          std::int64_t tick);

/// Gain of an item whose fade began at fade_begin_tick, at tick `tick`: 1 before, then linear to 0.
double fade_gain(std::int64_t fade_begin_tick, std::int64_t tick, std::int64_t ramp_ticks);

/// Whether the item is being removed or replaced by a newer version.
inline bool is_fading_out(const ItemRamp& ramp) {
  return ramp.fade_begin_tick != kNeverTick || ramp.superseded_at[0] != kNeverTick;
}

/// Gain of an item at tick `tick`: its fade-in times its fade-outs (see ItemRamp).
double ramp_gain(const ItemRamp& ramp, std::int64_t tick, std::int64_t ramp_ticks);

}  // namespace haptic::engine
