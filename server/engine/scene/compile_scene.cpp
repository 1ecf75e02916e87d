// Compiling a scene description into the flat per-stage arrays the loop evaluates
// (compiled_scene.hpp): off the loop, at every scene change; it allocates.
#include "engine/scene/compiled_scene.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <variant>

namespace haptic::engine {

namespace {

/// Whether a primitive can take the stateless fast path.
bool is_fast(const ObjectSpec& object) {
  return object.law == ContactLaw::kVelocity && object.static_friction == 0.0 &&
         object.object_mass == 0.0 &&
         object.dynamic_friction == 0.0 &&
         (std::holds_alternative<HalfSpaceSpec>(object.shape) ||
          std::holds_alternative<SphereSpec>(object.shape));
}

/// The radius of a sphere about the object's origin that holds the whole shape (a cheap early-out
/// for a far tool); infinite for an unbounded shape (a half-space or tangent plane).
double bounding_radius_of(const ObjectSpec& object) {
  return std::visit(
      [](const auto& shape) {
        using S = std::decay_t<decltype(shape)>;
        if constexpr (std::is_same_v<S, SphereSpec>) return shape.radius;
        if constexpr (std::is_same_v<S, BoxSpec>) return norm(shape.half_extents);
        if constexpr (std::is_same_v<S, CapsuleSpec>) return shape.radius + shape.half_length;
        return std::numeric_limits<double>::infinity();
      },
      object.shape);
}

/// compile_scene's work in progress: the scene it fills item by item, in the description's order
/// (the order carry_state's matching relies on), and what every item needs whatever its kind —
/// an energy meter and its owner's budget slot.
struct SceneBuilder {
  CompiledScene& scene;
  SceneState& state;

  /// Sizes the meters of `items` item versions on each of `ports` ports.
  void size_meters(std::size_t items, std::uint32_t ports) {
    state.ports = ports;
    state.meters.resize(items * ports);
    state.meter_keys.reserve(items);
    state.meter_ids.reserve(items);
    state.meter_sessions.reserve(items);
    state.meter_is_object.reserve(items);
    state.work_out = std::make_unique<std::atomic<double>[]>(items * ports);
    state.work_in = std::make_unique<std::atomic<double>[]>(items * ports);
  }

  /// The budget slot of a session's items, the session's first item opening it.
  std::uint32_t slot_of(std::uint64_t session_id) {
    auto& sessions = state.slot_sessions;
    const auto it = std::find(sessions.begin(), sessions.end(), session_id);
    if (it != sessions.end()) return static_cast<std::uint32_t>(it - sessions.begin());
    sessions.push_back(session_id);
    return static_cast<std::uint32_t>(sessions.size() - 1);
  }

  /// The next item's meter (port 0's index; every port has its own, meters_per_port apart).
  std::uint32_t new_meter(const ItemMeta& meta, bool is_object) {
    state.meter_keys.push_back(meta.state_key());
    state.meter_ids.push_back(meta.id);
    state.meter_sessions.push_back(meta.session_id);
    state.meter_is_object.push_back(is_object ? 1 : 0);
    return static_cast<std::uint32_t>(state.meter_keys.size() - 1);
  }

  /// An object goes to the cheapest stage that can render it.
  void add_object(const ObjectEntry& entry) {
    const std::uint32_t meter = new_meter(entry.meta, true);
    if (is_fast(entry.spec)) {
      add_fast_object(entry, meter);
    } else if (const auto* mesh = std::get_if<MeshShapeSpec>(&entry.spec.shape)) {
      add_mesh(entry, *mesh, meter);
    } else {
      add_contact(entry, meter);
    }
  }

  /// Stages 1 and 2: a frictionless half-space or sphere with the velocity law (no state).
  void add_fast_object(const ObjectEntry& entry, std::uint32_t meter) {
    const ObjectSpec& object = entry.spec;
    if (const auto* half_space = std::get_if<HalfSpaceSpec>(&object.shape)) {
      // Normalised after the rotation so a slightly non-unit quaternion cannot scale the force.
      const Vec3 n_W = rotate(object.R_WO, half_space->normal_O);
      assert(norm(n_W) > 0.0);
      scene.half_spaces.push_back(CompiledHalfSpace{object.p_WO, n_W * (1.0 / norm(n_W)),
                                                    object.stiffness, object.damping,
                                                    entry.meta.ramp(), meter,
                                                    slot_of(entry.meta.session_id)});
    } else {
      const auto& sphere = std::get<SphereSpec>(object.shape);
      scene.spheres.push_back(CompiledSphere{object.p_WO, sphere.radius, object.stiffness,
                                             object.damping, entry.meta.ramp(), meter,
                                             slot_of(entry.meta.session_id)});
    }
  }

  /// Stage 3: a primitive with state — a box, capsule or tangent plane, friction, a discrete
  /// impedance law or a virtual mass — and port 0's fresh ContactState for it.
  void add_contact(const ObjectEntry& entry, std::uint32_t meter) {
    const ObjectSpec& object = entry.spec;
    CompiledContact compiled;
    std::visit(
        [&](const auto& shape) {
          using S = std::decay_t<decltype(shape)>;
          if constexpr (std::is_same_v<S, TangentPlaneSpec>) {
            compiled.shape = HalfSpaceSpec{shape.normal_O};
            compiled.tangent_plane = true;
            compiled.reference_W = object.p_WO + rotate(object.R_WO, shape.reference_O);
            compiled.tangential_stiffness = shape.tangential_stiffness;
            compiled.tangential_damping = shape.tangential_damping;
          } else if constexpr (!std::is_same_v<S, MeshShapeSpec>) {
            compiled.shape = shape;
          }
        },
        object.shape);
    compiled.X_WO = ObjectPose{object.p_WO, object.R_WO};
    compiled.bounding_radius = bounding_radius_of(object);
    compiled.material = ContactMaterial{object.stiffness, object.damping, object.static_friction,
                                        object.dynamic_friction};
    compiled.law = object.law;
    if (object.law != ContactLaw::kVelocity) {
      compiled.weights = impedance_weights(
          ImpedanceParams{object.stiffness, object.damping, object.impedance_mass},
          discretization_of(object.law), scene.period_s);
    }
    compiled.object_mass = object.object_mass;
    if (object.object_mass > 0.0) scene.masses.push_back(static_cast<std::uint32_t>(scene.contacts.size()));
    compiled.object_damping = object.object_damping;
    const bool live = entry.meta.fade_begin_tick == kNeverTick && entry.meta.ramps.superseded_at[0] == kNeverTick;
    if (object.object_mass > 0.0 && object.across_sites && live) {
      // Only the live version is coupled: a fading one goes its own way out.
      scene.shared_masses.push_back(static_cast<std::uint32_t>(scene.contacts.size()));
      compiled.origin_site = object.origin_site;
      compiled.origin_id = object.origin_id != 0 ? object.origin_id : entry.meta.id;
    }
    compiled.ramp = entry.meta.ramp();
    compiled.state = static_cast<std::uint32_t>(state.contacts.size());
    compiled.meter = meter;
    compiled.slot = slot_of(entry.meta.session_id);
    ContactState contact_state;
    contact_state.key = entry.meta.state_key();
    contact_state.id = entry.meta.id;
    contact_state.filter = ImpedanceFilter(compiled.weights);
    state.contacts.push_back(contact_state);
    scene.contacts.push_back(std::move(compiled));
  }

  /// Stage 4: a triangle mesh and port 0's fresh god object for it (placed at its first tick).
  void add_mesh(const ObjectEntry& entry, const MeshShapeSpec& mesh, std::uint32_t meter) {
    const ObjectSpec& object = entry.spec;
    CompiledMesh compiled;
    compiled.model = mesh.model;
    compiled.pose = MeshPose{object.p_WO, object.R_WO, {}, {}};
    compiled.params.stiffness = object.stiffness;
    compiled.params.damping = object.damping;
    compiled.static_friction = object.static_friction;
    compiled.dynamic_friction = object.dynamic_friction;
    compiled.object_mass = object.object_mass;
    compiled.object_damping = object.object_damping;
    if (object.object_mass > 0.0) {
      scene.mesh_masses.push_back(static_cast<std::uint32_t>(scene.meshes.size()));
    }
    compiled.ramp = entry.meta.ramp();
    compiled.state = static_cast<std::uint32_t>(state.meshes.size());
    compiled.meter = meter;
    compiled.slot = slot_of(entry.meta.session_id);
    MeshState mesh_state;
    mesh_state.key = entry.meta.state_key();
    mesh_state.id = entry.meta.id;
    state.meshes.push_back(mesh_state);
    scene.meshes.push_back(std::move(compiled));
  }

  /// Stage 5 for a spring to a point, stage 6 for every other field.
  void add_field(const FieldEntry& entry) {
    const std::uint32_t meter = new_meter(entry.meta, false);
    if (const auto* spring = std::get_if<SpringToPointSpec>(&entry.spec.kind)) {
      scene.springs.push_back(CompiledSpring{spring->anchor_W, spring->stiffness, spring->damping,
                                             spring->max_force, entry.meta.ramp(), meter,
                                             slot_of(entry.meta.session_id)});
      return;
    }
    if (add_orientation_field(entry, meter)) return;
    CompiledField compiled;
    std::visit(
        [&](const auto& kind) {
          using K = std::decay_t<decltype(kind)>;
          if constexpr (std::is_constructible_v<EnergyFieldSpec, K>) compiled.spec = kind;
        },
        entry.spec.kind);
    compiled.ramp = entry.meta.ramp();
    compiled.meter = meter;
    compiled.slot = slot_of(entry.meta.session_id);
    scene.fields.push_back(std::move(compiled));
  }

  /// Stage 7: an orientation field and port 0's fresh state for it; false for any other field.
  bool add_orientation_field(const FieldEntry& entry, std::uint32_t meter) {
    CompiledOrientationField compiled;
    OrientationState orientation_state;
    if (const auto* spring = std::get_if<OrientationSpringSpec>(&entry.spec.kind)) {
      compiled.spec = *spring;
      orientation_state.spring.set_weights(orientation_spring_weights(*spring, scene.period_s));
    } else if (const auto* detent = std::get_if<OrientationDetentSpec>(&entry.spec.kind)) {
      compiled.spec = *detent;
    } else {
      return false;
    }
    compiled.ramp = entry.meta.ramp();
    compiled.state = static_cast<std::uint32_t>(state.orientations.size());
    compiled.meter = meter;
    compiled.slot = slot_of(entry.meta.session_id);
    orientation_state.key = entry.meta.state_key();
    orientation_state.id = entry.meta.id;
    state.orientations.push_back(orientation_state);
    scene.orientation_fields.push_back(std::move(compiled));
    return true;
  }

  /// Once every item is in: carry_state's scratch and the budget's per-slot sums, sized here so
  /// the loop allocates nothing, and every further port's state, a copy of port 0's fresh one.
  void size_per_port_state(std::size_t items) {
    state.meter_source.assign(state.meter_keys.size(), SceneState::kNoMeter);
    state.meter_taken.assign(state.meter_keys.size(), 0);
    state.slot_force.assign(state.slot_sessions.size(), Vec3{});
    state.slot_fields.assign(state.slot_sessions.size(), Vec3{});
    state.contacts_per_port = static_cast<std::uint32_t>(state.contacts.size());
    state.meshes_per_port = static_cast<std::uint32_t>(state.meshes.size());
    state.orientations_per_port = static_cast<std::uint32_t>(state.orientations.size());
    state.orientations.reserve(state.orientations.size() * state.ports);
    state.meters_per_port = static_cast<std::uint32_t>(items);
    state.contacts.reserve(state.contacts.size() * state.ports);
    state.meshes.reserve(state.meshes.size() * state.ports);
    for (std::uint32_t port = 1; port < state.ports; ++port) {
      for (std::uint32_t i = 0; i < state.contacts_per_port; ++i) state.contacts.push_back(state.contacts[i]);
      for (std::uint32_t i = 0; i < state.meshes_per_port; ++i) state.meshes.push_back(state.meshes[i]);
      for (std::uint32_t i = 0; i < state.orientations_per_port; ++i) {
        state.orientations.push_back(state.orientations[i]);
      }
    }
  }

  /// Every contact's and mesh's motion (one each, shared by the ports) starts at rest at its pose,
  /// which is what ObjectStates reads until the loop moves a virtual mass.
  void start_motions() {
    state.motions.assign(state.contacts_per_port, ContactMotion{});
    state.mesh_motions.assign(state.meshes_per_port, ContactMotion{});
    state.mesh_motion = std::make_unique<std::atomic<double>[]>(6 * state.meshes_per_port);
    for (const CompiledMesh& mesh : scene.meshes) {
      const Vec3& p = mesh.pose.p_WO;
      const double start[6] = {p.x, p.y, p.z, 0.0, 0.0, 0.0};
      for (int k = 0; k < 6; ++k) {
        state.mesh_motion[6 * mesh.state + k].store(start[k], std::memory_order_relaxed);
      }
    }
    state.motion = std::make_unique<std::atomic<double>[]>(6 * state.contacts_per_port);
    for (const CompiledContact& contact : scene.contacts) {
      const Vec3& p = contact.X_WO.p_WO;
      const double start[6] = {p.x, p.y, p.z, 0.0, 0.0, 0.0};
      for (int k = 0; k < 6; ++k) {
        state.motion[6 * contact.state + k].store(start[k], std::memory_order_relaxed);
      }
    }
  }

  /// The spheres' broad phase, where there are enough of them to need one, and its per-port
  /// lists sized so the loop allocates nothing.
  void build_sphere_grid() {
    const std::size_t n = scene.spheres.size();
    if (n < kSphereGridMinSpheres) return;
    std::vector<Vec3> centers;
    std::vector<double> radii;
    for (std::uint32_t i = 0; i < n; ++i) {
      const CompiledSphere& sphere = scene.spheres[i];
      centers.push_back(sphere.center_W);
      radii.push_back(sphere.radius);
      const ItemRamp& r = sphere.ramp;
      if (r.fade_begin_tick != kNeverTick || r.superseded_at[0] != kNeverTick) scene.fading_spheres.push_back(i);
    }
    scene.sphere_grid = SphereGrid(centers, radii);
    state.sphere_active.assign(2 * n * state.ports, 0);
    state.sphere_active_count.assign(state.ports, 0);
    state.sphere_active_side.assign(state.ports, 0);
    state.sphere_candidates.assign(2 * n * state.ports, 0);
    state.spheres_primed.assign(state.ports, 0);
  }

  /// The non-empty stages, so the loop skips an empty one with one branch.
  void mark_stages() {
    scene.stages = (scene.half_spaces.empty() ? 0u : kStageHalfSpaces) |
                   (scene.spheres.empty() ? 0u : kStageSpheres) |
                   (scene.contacts.empty() ? 0u : kStageContacts) |
                   (scene.meshes.empty() ? 0u : kStageMeshes) |
                   (scene.springs.empty() ? 0u : kStageSprings) |
                   (scene.fields.empty() ? 0u : kStageFields) |
                   (scene.sphere_grid.empty() ? 0u : kStageSphereGrid) |
                   (scene.orientation_fields.empty() ? 0u : kStageOrientation);
  }
};
}  // namespace

CompiledScene compile_scene(const SceneDescription& description, std::int64_t removal_ramp_ticks,
                            std::uint64_t generation, double period_s,
                            double session_force_budget, std::uint32_t ports) {
  assert(ports >= 1);
  ports = std::max<std::uint32_t>(1, ports);
  CompiledScene scene;
  scene.session_force_budget = session_force_budget;
  scene.removal_ramp_ticks = std::max<std::int64_t>(1, removal_ramp_ticks);
  scene.generation = generation;
  scene.period_s = period_s;
  SceneBuilder builder{scene, *scene.state};
  const std::size_t items = description.objects.size() + description.fields.size();
  builder.size_meters(items, ports);
  for (const ObjectEntry& entry : description.objects) builder.add_object(entry);
  for (const FieldEntry& entry : description.fields) builder.add_field(entry);
  builder.size_per_port_state(items);
  builder.start_motions();
  builder.build_sphere_grid();
  builder.mark_stages();
  return scene;
}

void drop_sphere_grid(CompiledScene& scene) {
  scene.sphere_grid = SphereGrid();
  scene.stages &= ~kStageSphereGrid;
}

}  // namespace haptic::engine
