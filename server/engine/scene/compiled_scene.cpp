#include "engine/scene/compiled_scene.hpp"

#include <algorithm>
#include <cassert>
#include <variant>

namespace haptic::engine {
namespace {

/// Shared contact law (half-space and sphere): the virtual wall V(s) = (K + Bs)/s of Eom et al.
/// (eq. 6-9) along the normal, clamped at zero so a surface only pushes; a damper that pulled
/// would hold the tool inside while it leaves. d is the penetration (m, > 0 in contact), n the
/// outward unit normal.
double contact_magnitude(double stiffness, double damping, double d, const Vec3& n, const Vec3& v) {
  return std::max(0.0, stiffness * d - damping * dot(v, n));
}

}  // namespace

double fade_gain(std::int64_t fade_begin_tick, std::int64_t tick, std::int64_t ramp_ticks) {
  assert(ramp_ticks >= 1);
  if (fade_begin_tick == kNeverTick || tick < fade_begin_tick) return 1.0;
  const double elapsed = static_cast<double>(tick - fade_begin_tick);
  const double ramp = static_cast<double>(std::max<std::int64_t>(1, ramp_ticks));
  return std::max(0.0, 1.0 - elapsed / ramp);
}

double ramp_gain(const ItemRamp& ramp, std::int64_t tick, std::int64_t ramp_ticks) {
  double gain = fade_gain(ramp.fade_begin_tick, tick, ramp_ticks);
  for (const std::int64_t superseded : ramp.superseded_at) gain *= fade_gain(superseded, tick, ramp_ticks);
  if (ramp.appear_tick != kAlwaysTick) gain *= 1.0 - fade_gain(ramp.appear_tick, tick, ramp_ticks);
  return gain;
}

CompiledScene compile_scene(const SceneDescription& description, std::int64_t removal_ramp_ticks,
                            std::uint64_t generation) {
  CompiledScene scene;
  scene.removal_ramp_ticks = std::max<std::int64_t>(1, removal_ramp_ticks);
  scene.generation = generation;
  // Exact sizes, so the arrays hold no slack and no push_back below reallocates.
  const auto half_space_count = std::count_if(
      description.objects.begin(), description.objects.end(),
      [](const ObjectEntry& e) { return std::holds_alternative<HalfSpaceSpec>(e.spec.shape); });
  scene.half_spaces.reserve(static_cast<std::size_t>(half_space_count));
  scene.spheres.reserve(description.objects.size() - static_cast<std::size_t>(half_space_count));
  scene.springs.reserve(description.fields.size());
  for (const ObjectEntry& entry : description.objects) {
    const ObjectSpec& object = entry.spec;
    if (const auto* half_space = std::get_if<HalfSpaceSpec>(&object.shape)) {
      // Normalised after the rotation so a slightly non-unit quaternion cannot scale the force.
      const Vec3 n_W = rotate(object.R_WO, half_space->normal_O);
      assert(norm(n_W) > 0.0);
      scene.half_spaces.push_back(CompiledHalfSpace{object.p_WO, n_W * (1.0 / norm(n_W)),
                                                    object.stiffness, object.damping,
                                                    entry.meta.ramp()});
    } else if (const auto* sphere = std::get_if<SphereSpec>(&object.shape)) {
      scene.spheres.push_back(CompiledSphere{object.p_WO, sphere->radius, object.stiffness,
                                             object.damping, entry.meta.ramp()});
    }
  }
  for (const FieldEntry& entry : description.fields) {
    if (const auto* spring = std::get_if<SpringToPointSpec>(&entry.spec.kind)) {
      scene.springs.push_back(CompiledSpring{spring->anchor_W, spring->stiffness, spring->damping,
                                             spring->max_force, entry.meta.ramp()});
    }
  }
  return scene;
}

SceneForce evaluate_scene(const CompiledScene& scene, const Vec3& p_WT, const Vec3& v_WT,
                          std::int64_t tick) {
  SceneForce out;
  out.p_WP = p_WT;
  double deepest = 0.0;
  const std::int64_t ramp = scene.removal_ramp_ticks;

  for (const CompiledHalfSpace& wall : scene.half_spaces) {
    if (is_fading_out(wall.ramp)) out.ramping = true;
    const double d = dot(wall.point_W - p_WT, wall.normal_W);
    if (d <= 0.0) continue;
    const double gain = ramp_gain(wall.ramp, tick, ramp);
    if (gain == 0.0) continue;
    out.F_T_W += (gain * contact_magnitude(wall.stiffness, wall.damping, d, wall.normal_W, v_WT)) *
                 wall.normal_W;
    ++out.contact_count;
    if (d > deepest) {
      deepest = d;
      out.p_WP = p_WT + d * wall.normal_W;
    }
  }

  for (const CompiledSphere& sphere : scene.spheres) {
    if (is_fading_out(sphere.ramp)) out.ramping = true;
    const Vec3 r = p_WT - sphere.center_W;
    const double distance = norm(r);
    const double d = sphere.radius - distance;
    if (d <= 0.0) continue;
    const double gain = ramp_gain(sphere.ramp, tick, ramp);
    if (gain == 0.0) continue;
    // At the exact centre the direction is undefined; push along +z.
    const Vec3 n = distance > 0.0 ? r * (1.0 / distance) : Vec3{0.0, 0.0, 1.0};
    out.F_T_W += (gain * contact_magnitude(sphere.stiffness, sphere.damping, d, n, v_WT)) * n;
    ++out.contact_count;
    if (d > deepest) {
      deepest = d;
      out.p_WP = sphere.center_W + sphere.radius * n;
    }
  }

  for (const CompiledSpring& spring : scene.springs) {
    if (is_fading_out(spring.ramp)) out.ramping = true;
    const double gain = ramp_gain(spring.ramp, tick, ramp);
    if (gain == 0.0) continue;
    // F = −∇U − b v with U = ½ k |p − anchor|².
    Vec3 F = -spring.stiffness * (p_WT - spring.anchor_W) - spring.damping * v_WT;
    if (spring.max_force > 0.0) {
      const double magnitude = norm(F);
      if (magnitude > spring.max_force) F *= spring.max_force / magnitude;
    }
    out.F_T_W += gain * F;
  }
  return out;
}

}  // namespace haptic::engine
