// Evaluating a compiled scene at a port's tool, and advancing its virtual masses: on the loop,
// every tick. No allocation, no lock, no throw (engine_no_allocation_test counts).
#include "engine/scene/compiled_scene.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <span>

namespace haptic::engine {
namespace {

/// Shared contact law (half-space and sphere): the virtual wall V(s) = (K + Bs)/s of Eom et al.
/// (eq. 6-9) along the normal, clamped at zero so a surface only pushes; a damper that pulled
/// would hold the tool inside while it leaves. d is the penetration (m, > 0 in contact), n the
/// outward unit normal.
double contact_magnitude(double stiffness, double damping, double d, const Vec3& n, const Vec3& v) {
  return std::max(0.0, stiffness * d - damping * dot(v, n));
}



/// Advances m Ẍ + B Ẋ = F (000 eq. 7.1) by dt with F held: with z = B dt / m,
///   Ẋ₁ = Ẋ₀ e^{−z} + (F/m) dt φ(z),  X₁ = X₀ + dt (Ẋ₀ φ(z) + (F/m) dt g(z)),
///   φ(z) = (1 − e^{−z})/z, g(z) = (z − 1 + e^{−z})/z² (series below z = 1e-3),
/// the same exact step as the point-mass plant's. m > 0.
void advance_virtual_mass(double m, double B, const Vec3& F, double dt, Vec3& X, Vec3& V) {
  const double z = B * dt / m;
  double phi, g;
  if (z < 1e-3) {
    phi = 1.0 - z / 2.0 + z * z / 6.0;
    g = 0.5 - z / 6.0 + z * z / 24.0;
  } else {
    const double e = std::exp(-z);
    phi = (1.0 - e) / z;
    g = (z - 1.0 + e) / (z * z);
  }
  const Vec3 a = (1.0 / m) * F;
  X += dt * (phi * V + (dt * g) * a);
  V = std::exp(-z) * V + (dt * phi) * a;
}

/// Coulomb friction on a mesh contact, the friction cone of Salisbury et al. 1995 on the god
/// object's result: the contact point sticks at an anchor on the surface (kept in O, so a moving
/// mesh carries it) while the tangential offset |t| from the frictionless proxy stays within
/// μ_s d (d the penetration along the contact normal), adding the friction spring K t; past the
/// cone the anchor slides to the dynamic cone, |t| = μ_d d. The anchor is projected onto the
/// primary constraint plane each tick (exact on a face; across an edge it follows the new face).
void apply_mesh_friction(const CompiledMesh& mesh, const MeshPose& pose, MeshState& s,
                         GodObjectOutput& g, const Vec3& p_WT) {
  if (!g.in_contact) {
    s.anchored = false;
    s.sliding = false;
    return;
  }
  const Vec3 to_proxy = g.p_WP - p_WT;
  const double distance = norm(to_proxy);
  const Vec3 n = g.plane_count > 0 ? g.normals_W[0]
                                   : (distance > 0.0 ? (1.0 / distance) * to_proxy : Vec3{0, 0, 1});
  const double d = dot(to_proxy, n);  // penetration along the contact normal. Unit: m.
  const ObjectPose X_WO{pose.p_WO, pose.R_WO};
  Vec3 p_stick = g.p_WP;
  if (s.anchored && d > 0.0) {
    const Vec3 a_W = to_world(X_WO, s.anchor_O);
    const Vec3 t = (a_W - dot(a_W - g.p_WP, n) * n) - g.p_WP;  // in the plane, from the proxy
    const double offset = norm(t);
    // Sticking holds up to the static cone; once sliding, it slides (on the dynamic cone) until
    // the tool comes back inside the dynamic cone.
    s.sliding = s.sliding ? offset > mesh.dynamic_friction * d : offset > mesh.static_friction * d;
    p_stick = s.sliding ? g.p_WP + (mesh.dynamic_friction * d / offset) * t : g.p_WP + t;
  }
  s.anchor_O = to_object(X_WO, p_stick);
  s.anchored = true;
  g.F_T_W += mesh.params.stiffness * (p_stick - g.p_WP);
  g.p_WP = p_stick;
}

/// Records one item's contribution this tick in its meter and publishes the totals. An item that
/// does no work now and did none at the last sample adds nothing: skipped, so idle items cost a
/// dot product.
inline void meter_power(SceneState& state, std::uint32_t index, double power, double dt) {
  EnergyMeter& m = state.meters[index];
  if (power == 0.0 && m.last_power == 0.0) {
    m.has_last = true;
    return;
  }
  m.add_power(power, dt);
  state.work_out[index].store(m.work_out, std::memory_order_relaxed);
  state.work_in[index].store(m.work_in, std::memory_order_relaxed);
}

inline void meter(SceneState& state, std::uint32_t index, const Vec3& F, const Vec3& v, double dt) {
  meter_power(state, index, dot(F, v), dt);
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
  // The common case — an item long since ramped in, neither removed nor replaced — costs three
  // compares. (superseded_at fills from its front.)
  if (ramp.fade_begin_tick == kNeverTick && ramp.superseded_at[0] == kNeverTick &&
      (ramp.appear_tick == kAlwaysTick || tick - ramp.appear_tick >= ramp_ticks)) {
    return 1.0;
  }
  double gain = fade_gain(ramp.fade_begin_tick, tick, ramp_ticks);
  for (const std::int64_t superseded : ramp.superseded_at) gain *= fade_gain(superseded, tick, ramp_ticks);
  if (ramp.appear_tick != kAlwaysTick) gain *= 1.0 - fade_gain(ramp.appear_tick, tick, ramp_ticks);
  return gain;
}

namespace {

/// What the stages of one port's evaluation share: the tool, this port's slices of the per-port
/// state, and the force being built. Each stage reads its compiled items, updates their state and
/// meters and adds their forces here, in a fixed order (docs/scene.md), MuJoCo-pipeline style.
struct PortPass {
  const CompiledScene& scene;
  SceneState& state;
  ContactState* contacts;   // this port's contact states
  MeshState* meshes;        // this port's mesh states
  std::uint32_t meters;     // this port's first meter
  const Vec3& p_WT;
  const Vec3& v_WT;
  std::int64_t tick;
  std::int64_t ramp_ticks;  // how long an item ramps in or out (removal_ramp_ticks)
  double dt;                // Unit: s.
  /// With a per-session budget each session's items add up apart first (clipped at the end).
  bool budgeted;
  SceneForce& out;          // p_WP: the surface point of the deepest contact so far, else p_WT
  double deepest = 0.0;     // that contact's penetration. Unit: m.

  /// Adds one item's force: to its owner's sums with a budget, else straight to the total.
  /// Keep the target chosen by reference as here: written as if/else, the compiler stores the
  /// running total to memory inside every stage's loop (same instructions, TickDefault 4–6 %
  /// slower on these machines).
  void contribute(std::uint32_t slot, const Vec3& F, bool field) {
    Vec3& total = budgeted ? state.slot_force[slot] : out.F_T_W;
    Vec3& fields = budgeted ? state.slot_fields[slot] : out.F_fields_W;
    total += F;
    if (field) fields += F;
  }
};

/// Stage 1: half-spaces, d = dot(point − p, n) the penetration (see contact_magnitude).
[[gnu::always_inline]] inline void add_half_spaces(PortPass& pass) {
  for (const CompiledHalfSpace& wall : pass.scene.half_spaces) {
    if (is_fading_out(wall.ramp, pass.tick, pass.ramp_ticks)) pass.out.ramping = true;
    const double d = dot(wall.point_W - pass.p_WT, wall.normal_W);
    const double gain = d > 0.0 ? ramp_gain(wall.ramp, pass.tick, pass.ramp_ticks) : 0.0;
    const Vec3 F =
        gain > 0.0
            ? (gain * contact_magnitude(wall.stiffness, wall.damping, d, wall.normal_W, pass.v_WT)) *
                  wall.normal_W
            : Vec3{};
    meter(pass.state, pass.meters + wall.meter, F, pass.v_WT, pass.dt);
    if (gain == 0.0) continue;
    pass.contribute(wall.slot, F, false);
    ++pass.out.contact_count;
    if (d > pass.deepest) {
      pass.deepest = d;
      pass.out.p_WP = pass.p_WT + d * wall.normal_W;
    }
  }
}

/// One sphere of stage 2: the same law as a half-space's along the radial direction. True when it
/// pushed (the tool is inside and the sphere's gain is above zero).
[[gnu::always_inline]] inline bool add_sphere(PortPass& pass, const CompiledSphere& sphere) {
  const Vec3 r = pass.p_WT - sphere.center_W;
  const double distance = norm(r);
  const double d = sphere.radius - distance;
  const double gain = d > 0.0 ? ramp_gain(sphere.ramp, pass.tick, pass.ramp_ticks) : 0.0;
  // At the exact centre the direction is undefined; push along +z.
  const Vec3 n = distance > 0.0 ? r * (1.0 / distance) : Vec3{0.0, 0.0, 1.0};
  const Vec3 F =
      gain > 0.0 ? (gain * contact_magnitude(sphere.stiffness, sphere.damping, d, n, pass.v_WT)) * n
                 : Vec3{};
  meter(pass.state, pass.meters + sphere.meter, F, pass.v_WT, pass.dt);
  if (gain == 0.0) return false;
  pass.contribute(sphere.slot, F, false);
  ++pass.out.contact_count;
  if (d > pass.deepest) {
    pass.deepest = d;
    pass.out.p_WP = sphere.center_W + sphere.radius * n;
  }
  return true;
}

/// Stage 2: spheres, every one of them.
[[gnu::always_inline]] inline void add_spheres(PortPass& pass) {
  for (const CompiledSphere& sphere : pass.scene.spheres) {
    if (is_fading_out(sphere.ramp, pass.tick, pass.ramp_ticks)) pass.out.ramping = true;
    add_sphere(pass, sphere);
  }
}

/// Stage 2 through the broad phase: the spheres listed in the tool's cell and those it touched
/// last tick (whose meters must see the contact end), each once, in index order — so the forces
/// add up in the same order, bit for bit, as add_spheres'. A sphere it skips is one the tool is
/// outside of, whose meter add_spheres would leave as it is (no power now or on the last tick).
/// The port's first tick looks at every sphere (as add_spheres), which leaves every meter as
/// add_spheres would have and starts the list of those touched.
// Not inlined: the function that runs every stage keeps the small frame a scene without it needs.
[[gnu::noinline]] void add_spheres_through_grid(PortPass& pass, std::uint32_t port) {
  const CompiledScene& scene = pass.scene;
  SceneState& state = pass.state;
  const std::size_t n = scene.spheres.size();
  const std::uint8_t side = state.sphere_active_side[port];
  const std::uint32_t* last = state.sphere_active.data() + (2 * port + side) * n;
  std::uint32_t* next = state.sphere_active.data() + (2 * port + (1 - side)) * n;
  std::uint32_t touched = 0;
  if (state.spheres_primed[port] == 0) {
    for (std::uint32_t i = 0; i < n; ++i) {
      const CompiledSphere& sphere = scene.spheres[i];
      if (is_fading_out(sphere.ramp, pass.tick, pass.ramp_ticks)) pass.out.ramping = true;
      if (add_sphere(pass, sphere)) next[touched++] = i;
    }
    state.spheres_primed[port] = 1;
  } else {
    for (const std::uint32_t i : scene.fading_spheres) {
      if (is_fading_out(scene.spheres[i].ramp, pass.tick, pass.ramp_ticks)) pass.out.ramping = true;
    }
    // Last tick's touched spheres and this cell's, merged (both ascending) without repeats.
    const std::span<const std::uint32_t> cell = scene.sphere_grid.candidates(pass.p_WT);
    std::uint32_t* candidates = state.sphere_candidates.data() + 2 * port * n;
    const std::uint32_t* a = last;
    const std::uint32_t* a_end = last + state.sphere_active_count[port];
    const std::uint32_t* b = cell.data();
    const std::uint32_t* b_end = cell.data() + cell.size();
    std::uint32_t count = 0;
    while (a != a_end || b != b_end) {
      const std::uint32_t i = (b == b_end || (a != a_end && *a < *b)) ? *a++ : *b++;
      if (count == 0 || candidates[count - 1] != i) candidates[count++] = i;
    }
    for (std::uint32_t k = 0; k < count; ++k) {
      const std::uint32_t i = candidates[k];
      if (add_sphere(pass, scene.spheres[i])) next[touched++] = i;
    }
  }
  state.sphere_active_count[port] = touched;
  state.sphere_active_side[port] = static_cast<std::uint8_t>(1 - side);
}

/// Stage 3: stateful contacts, each through its proxy (the velocity law, friction) or its
/// impedance filter; a virtual mass is met where it has moved to, and takes −F.
[[gnu::always_inline]] inline void add_contacts(PortPass& pass) {
  for (const CompiledContact& contact : pass.scene.contacts) {
    if (is_fading_out(contact.ramp, pass.tick, pass.ramp_ticks)) pass.out.ramping = true;
    ContactState& s = pass.contacts[contact.state];
    const double gain = ramp_gain(contact.ramp, pass.tick, pass.ramp_ticks);
    const bool moves = contact.object_mass > 0.0;
    ContactMotion& motion = pass.state.motions[contact.state];
    const ObjectPose X_WO = moves ? ObjectPose{contact.X_WO.p_WO + motion.displacement_W, contact.X_WO.R_WO}
                                  : contact.X_WO;
    const Vec3 v_rel = moves ? pass.v_WT - motion.velocity_W : pass.v_WT;  // the tool relative to the object
    ContactForce force;
    const Vec3 from_centre = pass.p_WT - X_WO.p_WO;
    if (dot(from_centre, from_centre) > contact.bounding_radius * contact.bounding_radius) {
      // The tool is outside the shape's bounding sphere: no contact, and no shape query.
      s.proxy.reset();
      s.touching = false;
      force.p_WP = pass.p_WT;
    } else if (contact.law == ContactLaw::kVelocity) {
      force = s.proxy.update(contact.shape, X_WO, contact.material, pass.p_WT, v_rel);
    } else {
      // A discrete impedance on the sampled penetration along the closest point's normal.
      const ShapeQuery q = query(contact.shape, X_WO, pass.p_WT);
      if (q.signed_distance < 0.0) {
        if (!s.touching) {
          s.filter.reset();
          s.touching = true;
        }
        force.penetration = -q.signed_distance;
        force.n_W = q.n_W;
        force.p_WP = q.p_WS;
        force.in_contact = true;
        force.F_T_W = std::max(0.0, s.filter.update(force.penetration)) * q.n_W;
      } else {
        s.touching = false;
        force.p_WP = pass.p_WT;
      }
    }
    if (contact.tangent_plane && force.in_contact) {
      // Russo ch. 5: within the plane, a spring-damper about the surface reference point.
      const Vec3& n = force.n_W;
      const Vec3 offset = pass.p_WT - contact.reference_W;
      const Vec3 offset_t = offset - dot(offset, n) * n;
      const Vec3 v_t = v_rel - dot(v_rel, n) * n;
      force.F_T_W += -contact.tangential_stiffness * offset_t - contact.tangential_damping * v_t;
    }
    const Vec3 F = gain * force.F_T_W;
    meter(pass.state, pass.meters + contact.meter, F, pass.v_WT, pass.dt);
    // The mass moves in advance_scene, under every port's reaction.
    if (moves) motion.reaction_W += -1.0 * F;
    if (!force.in_contact || gain == 0.0) continue;
    pass.contribute(contact.slot, F, false);
    ++pass.out.contact_count;
    if (force.penetration > pass.deepest) {
      pass.deepest = force.penetration;
      pass.out.p_WP = force.p_WP;
    }
  }
}

/// Stage 4: meshes, each through its god object (rebased first after a change of version), with
/// friction on top where the material has it.
[[gnu::always_inline]] inline void add_meshes(PortPass& pass) {
  for (const CompiledMesh& mesh : pass.scene.meshes) {
    if (is_fading_out(mesh.ramp, pass.tick, pass.ramp_ticks)) pass.out.ramping = true;
    MeshState& s = pass.meshes[mesh.state];
    const bool moves = mesh.object_mass > 0.0;
    ContactMotion& motion = pass.state.mesh_motions[mesh.state];
    const MeshPose pose = moves ? MeshPose{mesh.pose.p_WO + motion.displacement_W, mesh.pose.R_WO,
                                           motion.velocity_W, {}}
                                : mesh.pose;
    if (!s.god.initialized) reset_god_object(s.god, pose, pass.p_WT);
    if (s.needs_rebase) {
      rebase_god_object(s.god, mesh.model->bvh, pose, mesh.params);
      s.needs_rebase = false;
    }
    GodObjectOutput g = update_god_object(s.god, mesh.model->bvh, pose, mesh.params, pass.p_WT, pass.v_WT);
    if (mesh.static_friction > 0.0) apply_mesh_friction(mesh, pose, s, g, pass.p_WT);
    const double gain = ramp_gain(mesh.ramp, pass.tick, pass.ramp_ticks);
    const Vec3 F = gain * g.F_T_W;
    meter(pass.state, pass.meters + mesh.meter, F, pass.v_WT, pass.dt);
    if (moves) motion.reaction_W += -1.0 * F;  // moved once per tick by advance_scene
    if (!g.in_contact || gain == 0.0) continue;
    pass.contribute(mesh.slot, F, false);
    ++pass.out.contact_count;
    const double depth = norm(g.p_WP - pass.p_WT);
    if (depth > pass.deepest) {
      pass.deepest = depth;
      pass.out.p_WP = g.p_WP;
    }
  }
}

/// Stage 5: springs to a point.
[[gnu::always_inline]] inline void add_springs(PortPass& pass) {
  for (const CompiledSpring& spring : pass.scene.springs) {
    if (is_fading_out(spring.ramp, pass.tick, pass.ramp_ticks)) pass.out.ramping = true;
    const double gain = ramp_gain(spring.ramp, pass.tick, pass.ramp_ticks);
    // F = −∇U − b v with U = ½ k |p − anchor|².
    Vec3 F = clip_norm(-spring.stiffness * (pass.p_WT - spring.anchor_W) - spring.damping * pass.v_WT,
                       spring.max_force);
    F *= gain;
    meter(pass.state, pass.meters + spring.meter, F, pass.v_WT, pass.dt);
    pass.contribute(spring.slot, F, true);
  }
}

/// Stage 6: every other energy field.
[[gnu::always_inline]] inline void add_fields(PortPass& pass) {
  for (const CompiledField& field : pass.scene.fields) {
    if (is_fading_out(field.ramp, pass.tick, pass.ramp_ticks)) pass.out.ramping = true;
    const double gain = ramp_gain(field.ramp, pass.tick, pass.ramp_ticks);
    const Vec3 F = gain * evaluate_field(field.spec, pass.p_WT, pass.v_WT).F_T_W;
    meter(pass.state, pass.meters + field.meter, F, pass.v_WT, pass.dt);
    pass.contribute(field.slot, F, true);
  }
}

/// Each session's force (its fields' part scaled alike) is clipped to the budget before the
/// sessions add up; the server's own items (session 0) are exempt.
[[gnu::always_inline]] inline void clip_to_session_budgets(PortPass& pass) {
  const SceneState& state = pass.state;
  const double budget = pass.scene.session_force_budget;
  for (std::size_t slot = 0; slot < state.slot_force.size(); ++slot) {
    const Vec3& F = state.slot_force[slot];
    const double magnitude = norm(F);
    const bool clip = state.slot_sessions[slot] != 0 && magnitude > budget;
    const double scale = clip ? budget / magnitude : 1.0;
    pass.out.F_T_W += scale * F;
    pass.out.F_fields_W += scale * state.slot_fields[slot];
  }
}

/// evaluate_scene_port's body, inlined into both entry points so that evaluate_scene's port 0
/// costs nothing over a scene with one port. The stages run in a fixed order; an empty one costs
/// a branch.
[[gnu::always_inline]] inline SceneForce evaluate_port(const CompiledScene& scene, std::uint32_t port,
                                                       const Vec3& p_WT, const Vec3& v_WT,
                                                       std::int64_t tick, double dt) {
  SceneState& state = *scene.state;
  assert(port < state.ports);
  SceneForce out;
  out.p_WP = p_WT;
  PortPass pass{.scene = scene,
                .state = state,
                .contacts = state.contacts.data() + std::size_t{port} * state.contacts_per_port,
                .meshes = state.meshes.data() + std::size_t{port} * state.meshes_per_port,
                .meters = port * state.meters_per_port,
                .p_WT = p_WT,
                .v_WT = v_WT,
                .tick = tick,
                .ramp_ticks = scene.removal_ramp_ticks,
                .dt = dt,
                .budgeted = scene.session_force_budget > 0.0,
                .out = out};
  if (pass.budgeted) {
    std::fill(state.slot_force.begin(), state.slot_force.end(), Vec3{});
    std::fill(state.slot_fields.begin(), state.slot_fields.end(), Vec3{});
  }
  if (scene.stages & kStageHalfSpaces) add_half_spaces(pass);
  if (scene.stages & kStageSpheres) {  // a scene without spheres tests one bit, as before
    if (scene.stages & kStageSphereGrid) {
      add_spheres_through_grid(pass, port);
    } else {
      add_spheres(pass);
    }
  }
  if (scene.stages & kStageContacts) add_contacts(pass);
  if (scene.stages & kStageMeshes) add_meshes(pass);
  if (scene.stages & kStageSprings) add_springs(pass);
  if (scene.stages & kStageFields) add_fields(pass);
  if (pass.budgeted) clip_to_session_budgets(pass);
  return out;
}

}  // namespace

SceneForce evaluate_scene_port(const CompiledScene& scene, std::uint32_t port, const Vec3& p_WT,
                               const Vec3& v_WT, std::int64_t tick, double dt) {
  return evaluate_port(scene, port, p_WT, v_WT, tick, dt);
}

SceneTorque evaluate_scene_orientation(const CompiledScene& scene, std::uint32_t port,
                                       const Quat& R_WT, const Vec3& w_WT, std::int64_t tick,
                                       double dt) {
  SceneState& state = *scene.state;
  assert(port < state.ports);
  OrientationState* states = state.orientations.data() + std::size_t{port} * state.orientations_per_port;
  const std::uint32_t meters = port * state.meters_per_port;
  SceneTorque out;
  for (const CompiledOrientationField& field : scene.orientation_fields) {
    if (is_fading_out(field.ramp, tick, scene.removal_ramp_ticks)) out.ramping = true;
    const double gain = ramp_gain(field.ramp, tick, scene.removal_ramp_ticks);
    OrientationState& field_state = states[field.state];
    // A spring's filters run every tick, whatever its gain, so a fading one keeps its history.
    const OrientationSample sample =
        std::holds_alternative<OrientationSpringSpec>(field.spec)
            ? field_state.spring.update(std::get<OrientationSpringSpec>(field.spec), R_WT, w_WT, dt)
            : evaluate_orientation_detent(std::get<OrientationDetentSpec>(field.spec), R_WT, w_WT);
    const Vec3 tau = gain * sample.tau_T_W;
    meter_power(state, meters + field.meter, dot(tau, w_WT), dt);
    out.tau_T_W += tau;
  }
  return out;
}

MassNow mass_now(const CompiledScene& scene, std::uint32_t contact) {
  const CompiledContact& compiled = scene.contacts[contact];
  const ContactMotion& m = scene.state->motions[compiled.state];
  return {compiled.X_WO.p_WO + m.displacement_W, m.velocity_W};
}

void push_mass(const CompiledScene& scene, std::uint32_t contact, const Vec3& F) {
  scene.state->motions[scene.contacts[contact].state].reaction_W += F;
}

void place_mass(const CompiledScene& scene, std::uint32_t contact, const Vec3& p_WO, const Vec3& v_WO) {
  const CompiledContact& compiled = scene.contacts[contact];
  ContactMotion& m = scene.state->motions[compiled.state];
  m.displacement_W = p_WO - compiled.X_WO.p_WO;
  m.velocity_W = v_WO;
}

void advance_scene(const CompiledScene& scene, double dt) {
  SceneState& state = *scene.state;
  for (const std::uint32_t index : scene.masses) {
    const CompiledContact& contact = scene.contacts[index];
    ContactMotion& m = state.motions[contact.state];
    // 000 eq. 7.1 under the ports' reactions held over the tick, integrated exactly.
    advance_virtual_mass(contact.object_mass, contact.object_damping, m.reaction_W, dt,
                         m.displacement_W, m.velocity_W);
    m.reaction_W = Vec3{};
    const Vec3 p = contact.X_WO.p_WO + m.displacement_W;
    const double now[6] = {p.x, p.y, p.z, m.velocity_W.x, m.velocity_W.y, m.velocity_W.z};
    for (int k = 0; k < 6; ++k) state.motion[6 * contact.state + k].store(now[k], std::memory_order_relaxed);
  }
  for (const std::uint32_t index : scene.mesh_masses) {
    const CompiledMesh& mesh = scene.meshes[index];
    ContactMotion& m = state.mesh_motions[mesh.state];
    advance_virtual_mass(mesh.object_mass, mesh.object_damping, m.reaction_W, dt, m.displacement_W,
                         m.velocity_W);
    m.reaction_W = Vec3{};
    const Vec3 p = mesh.pose.p_WO + m.displacement_W;
    const double now[6] = {p.x, p.y, p.z, m.velocity_W.x, m.velocity_W.y, m.velocity_W.z};
    for (int k = 0; k < 6; ++k) state.mesh_motion[6 * mesh.state + k].store(now[k], std::memory_order_relaxed);
  }
}

SceneForce evaluate_scene(const CompiledScene& scene, const Vec3& p_WT, const Vec3& v_WT,
                          std::int64_t tick, double dt) {
  const SceneForce out = evaluate_port(scene, 0, p_WT, v_WT, tick, dt);
  if (!scene.masses.empty() || !scene.mesh_masses.empty()) advance_scene(scene, dt);
  return out;
}


}  // namespace haptic::engine
