#pragma once
// The scene compiled for the loop: one flat array per stage, world-frame geometry precomputed,
// nothing the scene does not use (docs/scene.md lists the stages). The geometry and parameters are
// immutable once built; the loop reads them through a pointer handed over by
// runtime/SnapshotExchange and never allocates or frees them.
//
// What must outlive a snapshot — contact proxies, impedance filters' past samples, god objects,
// energy meters — lives in the snapshot's SceneState, written only by the loop. When the loop
// adopts a newer snapshot it carries each item version's state across by key (carry_state), so
// an unrelated change elsewhere in the scene never resets a contact.

#include <atomic>
#include <cstdint>
#include <memory>
#include <variant>
#include <vector>

#include "engine/core/vec3.hpp"
#include "engine/scene/contact_proxy.hpp"
#include "engine/scene/fields.hpp"
#include "engine/scene/god_object.hpp"
#include "engine/scene/impedance.hpp"
#include "engine/scene/orientation_fields.hpp"
#include "engine/scene/scene_spec.hpp"
#include "engine/scene/shapes.hpp"
#include "engine/scene/sphere_grid.hpp"

namespace haptic::engine {

/// Stage 1, the fast path: a frictionless half-space with the measured-velocity law. Stateless.
struct CompiledHalfSpace {
  Vec3 point_W;       // A point on the surface. Unit: m.
  Vec3 normal_W;      // Unit outward normal.
  double stiffness;   // Unit: N/m.
  double damping;     // Unit: N*s/m.
  ItemRamp ramp;
  std::uint32_t meter = 0;  // index into SceneState::meters
  std::uint32_t slot = 0;   // the owner's index into SceneState::slot_sessions
};

/// Stage 2, the fast path: a frictionless sphere with the measured-velocity law. Stateless.
struct CompiledSphere {
  Vec3 center_W;      // Unit: m.
  double radius;      // Unit: m.
  double stiffness;   // Unit: N/m.
  double damping;     // Unit: N*s/m.
  ItemRamp ramp;
  std::uint32_t meter = 0;
  std::uint32_t slot = 0;
};

/// Stage 3: any primitive that needs state — a box or capsule, friction (a ContactProxy), or a
/// discretized impedance law (an ImpedanceFilter on the penetration).
struct CompiledContact {
  PrimitiveShape shape;
  ObjectPose X_WO;
  ContactMaterial material;
  ContactLaw law = ContactLaw::kVelocity;
  ImpedanceWeights weights;  // for the discrete laws
  /// Radius of a sphere about X_WO.p_WO that holds the whole shape (a cheap early-out for a
  /// far tool); infinite for a half-space or tangent plane. Unit: m.
  double bounding_radius = 0.0;
  /// A tangent plane (Russo ch. 5): the shape is its half-space; in contact, a tangential
  /// spring-damper pulls the tool towards reference_W within the plane.
  bool tangent_plane = false;
  Vec3 reference_W;             // Unit: m.
  double tangential_stiffness = 0.0;  // Unit: N/m.
  double tangential_damping = 0.0;    // Unit: N·s/m.
  double object_mass = 0.0;     // > 0: a virtual mass that moves (000 eq. 7.1). Unit: kg.
  double object_damping = 0.0;  // B_V. Unit: N·s/m.
  /// A virtual mass shared across sites: its key (ObjectSpec::origin_site, origin_id, the id
  /// resolved to the item's own where 0).
  SiteKey origin_site;
  std::uint64_t origin_id = 0;
  ItemRamp ramp;
  std::uint32_t state = 0;   // index into SceneState::contacts
  std::uint32_t meter = 0;
  std::uint32_t slot = 0;
};

/// Stage 4: a triangle mesh rendered with a god object.
struct CompiledMesh {
  std::shared_ptr<const MeshModel> model;
  MeshPose pose;
  GodObjectParams params;
  double object_mass = 0.0;       // > 0: a virtual mass that moves (000 eq. 7.1). Unit: kg.
  double object_damping = 0.0;    // B_V. Unit: N·s/m.
  double static_friction = 0.0;   // μ_s of the material (0: the god object slides freely).
  double dynamic_friction = 0.0;  // μ_d ≤ μ_s.
  ItemRamp ramp;
  std::uint32_t state = 0;   // index into SceneState::meshes
  std::uint32_t meter = 0;
  std::uint32_t slot = 0;
};

/// Stage 5: a spring pulling the tool to a point (the original field).
struct CompiledSpring {
  Vec3 anchor_W;      // Unit: m.
  double stiffness;   // Unit: N/m.
  double damping;     // Unit: N*s/m.
  double max_force;   // Unit: N; 0 = no clip.
  ItemRamp ramp;
  std::uint32_t meter = 0;
  std::uint32_t slot = 0;
};

/// Stage 6: every other energy field (engine/scene/fields).
struct CompiledField {
  EnergyFieldSpec spec;
  ItemRamp ramp;
  std::uint32_t meter = 0;
  std::uint32_t slot = 0;
};

/// Stage 7: orientation fields, torques on the tool's orientation (evaluate_scene_orientation;
/// only for ports whose device measures orientation).
struct CompiledOrientationField {
  std::variant<OrientationSpringSpec, OrientationDetentSpec> spec;
  ItemRamp ramp;
  std::uint32_t state = 0;  // index into SceneState::orientations (per port)
  std::uint32_t meter = 0;
  std::uint32_t slot = 0;
};

/// Per item-version state of an orientation field that belongs to one tool (one per port): a
/// spring's filters (a detent has none, but keeps its slot so indices stay simple).
struct OrientationState {
  std::uint64_t key = 0;
  std::uint64_t id = 0;   // the item; a new version of it inherits the filters' history
  OrientationSpringState spring;
};

/// Per item-version state of a stateful contact that belongs to one tool (one per port).
struct ContactState {
  std::uint64_t key = 0;
  std::uint64_t id = 0;   // the item; a new version of it inherits the proxy and filter
  ContactProxy proxy;
  ImpedanceFilter filter;
  bool touching = false;  // the filter's contact has started
};

/// Per item-version motion of a stateful contact, shared by every port: a virtual mass moves once
/// per tick under the reactions of all the tools touching it (000 eq. 7.1).
struct ContactMotion {
  Vec3 displacement_W;  // X(t), its origin's displacement from its pose. Unit: m.
  Vec3 velocity_W;      // Ẋ(t). Unit: m/s.
  Vec3 reaction_W;      // This tick's reactions −F summed over the ports so far. Unit: N.
};

/// Per item-version state of a mesh that belongs to one tool (one per port).
struct MeshState {
  std::uint64_t key = 0;
  std::uint64_t id = 0;        // the item; a new version of it inherits the god object
  GodObjectState god;
  bool needs_rebase = false;   // inherited from an earlier version of the mesh
  /// Friction: where the contact sticks, in O (the frictionless god object's proxy slides; this
  /// point holds while the tool stays inside the static cone).
  Vec3 anchor_O;
  bool anchored = false;
  bool sliding = false;   // kinetic friction until the tool is back inside the dynamic cone
};

/// What the loop writes. What belongs to one tool is held once per port, port-major: port p's
/// entry for contact state i is contacts[p * contacts_per_port + i], and likewise for meshes and
/// meters (meters_per_port is the number of items). Meters are reported through relaxed atomics
/// (work_out, work_in per meter and port), read off the loop for GetSceneEnergy.
struct SceneState {
  std::uint32_t ports = 1;                // tools evaluated against the scene each tick; >= 1
  std::uint32_t contacts_per_port = 0;
  std::uint32_t meshes_per_port = 0;
  std::uint32_t meters_per_port = 0;
  std::uint32_t orientations_per_port = 0;
  std::vector<ContactState> contacts;     // per port
  std::vector<OrientationState> orientations;  // per port
  std::vector<ContactMotion> motions;     // per contact state, shared by the ports
  std::vector<ContactMotion> mesh_motions;  // per mesh state, shared by the ports
  std::unique_ptr<std::atomic<double>[]> mesh_motion;  // 6 per mesh, as `motion`
  std::vector<MeshState> meshes;          // per port
  std::vector<EnergyMeter> meters;        // per port
  std::vector<std::uint64_t> meter_keys;  // the item version each meter belongs to (per item)
  /// carry_state's scratch, sized at compile so adoption allocates nothing: for each meter the
  /// older snapshot's meter it continues (or kNoMeter), and whether a newer snapshot took it.
  std::vector<std::uint32_t> meter_source;
  std::vector<std::uint8_t> meter_taken;
  static constexpr std::uint32_t kNoMeter = 0xffffffffu;
  std::vector<std::uint64_t> meter_ids;   // the item (for reports)
  std::vector<std::uint64_t> meter_sessions;  // its owner (for reports)
  std::vector<std::uint8_t> meter_is_object;  // 1: an object, 0: a field
  std::unique_ptr<std::atomic<double>[]> work_out;  // J given to the device, per meter and port
  std::unique_ptr<std::atomic<double>[]> work_in;   // J absorbed from the device, per meter and port
  /// Virtual masses' position and velocity (6 per contact: x, y, z, ẋ, ẏ, ż in W), published each
  /// tick for ObjectStates. Units: m, m/s.
  std::unique_ptr<std::atomic<double>[]> motion;
  /// The sessions that own items, and per session one port's force this tick and its fields' part
  /// (used only with a per-session force budget; cleared at the start of every port's evaluation,
  /// so ports are evaluated one after another, on the loop). Units: N.
  std::vector<std::uint64_t> slot_sessions;
  std::vector<Vec3> slot_force;
  std::vector<Vec3> slot_fields;
  /// The sphere stage's broad phase (with CompiledScene::sphere_grid), per port: the spheres in
  /// contact on the last tick (two lists of `spheres` entries, flipped each tick: they must be
  /// looked at once more, so their meters see the contact end), a scratch list of this tick's
  /// candidates, and whether the port's first tick — which looks at every sphere, as the stage
  /// without a grid does every tick — has run.
  std::vector<std::uint32_t> sphere_active;       // 2 × spheres per port
  std::vector<std::uint32_t> sphere_active_count;  // per port
  std::vector<std::uint8_t> sphere_active_side;    // per port: which of the two lists is last tick's
  std::vector<std::uint32_t> sphere_candidates;    // 2 × spheres per port
  std::vector<std::uint8_t> spheres_primed;        // per port
};

/// Which stages a compiled scene runs (docs/scene.md); an empty stage is skipped entirely.
enum SceneStage : std::uint32_t {
  kStageHalfSpaces = 1u << 0,
  kStageSpheres = 1u << 1,
  kStageContacts = 1u << 2,
  kStageMeshes = 1u << 3,
  kStageSprings = 1u << 4,
  kStageFields = 1u << 5,
  kStageSphereGrid = 1u << 6,  // the sphere stage through its broad phase
  kStageOrientation = 1u << 7,  // orientation fields (evaluate_scene_orientation)
};

struct CompiledScene {
  std::vector<CompiledHalfSpace> half_spaces;
  std::vector<CompiledSphere> spheres;
  std::vector<CompiledContact> contacts;
  std::vector<CompiledMesh> meshes;
  std::vector<CompiledSpring> springs;
  std::vector<CompiledField> fields;
  std::vector<CompiledOrientationField> orientation_fields;
  /// The contacts that are virtual masses (indices into `contacts`), which advance_scene moves.
  std::vector<std::uint32_t> masses;
  /// The meshes that are virtual masses (indices into `meshes`).
  std::vector<std::uint32_t> mesh_masses;
  /// The virtual masses shared across sites (indices into `contacts`, live versions only), which
  /// the loop couples to the other sites' copies before advance_scene (runtime/shared_masses).
  std::vector<std::uint32_t> shared_masses;
  /// The spheres' broad phase: built from kSphereGridMinSpheres spheres on (kStageSphereGrid);
  /// with it a tick looks only at the spheres listed where the tool is, those it touched last
  /// tick, and those fading out (fading_spheres, for SceneForce::ramping).
  SphereGrid sphere_grid;
  std::vector<std::uint32_t> fading_spheres;
  std::uint32_t stages = 0;              // SceneStage bits of the non-empty stages
  std::int64_t removal_ramp_ticks = 50;  // Ticks over which an item ramps in or out; >= 1.
  /// Largest force one session's items may exert together (the server's own scene is exempt);
  /// 0: no budget. Unit: N.
  double session_force_budget = 0.0;
  double period_s = 1e-3;                // The loop period the discrete laws were built for.
  std::uint64_t generation = 0;          // Increases with every published scene.
  /// Which run the scene belongs to: a lockstep reset starts another, and carry_state carries
  /// nothing across runs (ids are reused, so an item must not inherit its namesake's state).
  std::uint64_t run = 0;
  std::unique_ptr<SceneState> state = std::make_unique<SceneState>();  // written by the loop only
};

/// Makes the sphere stage look at every sphere every tick, as it does without a grid (for tests
/// and benchmarks that compare the two). Off the loop.
void drop_sphere_grid(CompiledScene& scene);

/// Flattens a description into a compiled scene (off the loop; allocates). period_s: the loop
/// period (s), for the discrete impedance laws. ports: how many tools (one per device) are
/// evaluated against the scene each tick, each with its own contact state and meters; >= 1.
CompiledScene compile_scene(const SceneDescription& description, std::int64_t removal_ramp_ticks,
                            std::uint64_t generation, double period_s = 1e-3,
                            double session_force_budget = 0.0, std::uint32_t ports = 1);

/// On the loop, when it adopts `to` after `from`: copies every item version's state that both
/// hold (matched by key), per port for each port both hold (a port only `to` has starts fresh)
/// and once for a virtual mass's motion; a version new in `to` inherits its item's newest old
/// version's proxy, filter history and motion, and a mesh version its god object, rebased onto its
/// new geometry at its first tick; the energy of a version that `to` no longer holds is added to
/// a version of the same item that it does, so an item's totals survive its updates. Nothing
/// when the two belong to different runs (CompiledScene::run). Does not allocate.
void carry_state(const CompiledScene& from, const CompiledScene& to);

/// A virtual mass's state, read off the loop.
struct ObjectMotion {
  std::uint64_t id = 0;
  Vec3 p_WO;  // Where its origin is now. Unit: m.
  Vec3 v_WO;  // Unit: m/s.
};

/// Off the loop: every virtual mass in `scene` (the newest version of each item).
std::vector<ObjectMotion> object_motions(const CompiledScene& scene);

/// One item's energy totals, read off the loop.
struct ItemEnergyTotals {
  std::uint64_t id = 0;
  std::uint64_t session_id = 0;
  bool is_object = false;
  double given = 0.0;     // Work done on the tool. Unit: J.
  double absorbed = 0.0;  // Work done by the tool. Unit: J.
};

/// Off the loop: the energy totals of every item in `scene`, versions of one item and ports
/// summed, in item order. Reads the loop's relaxed atomics (a total may be a tick older than another).
std::vector<ItemEnergyTotals> energy_totals(const CompiledScene& scene);

/// What the scene asks of the device at one tick.
struct SceneForce {
  Vec3 F_T_W;                    // Force on the tool, in W. Unit: N.
  Vec3 F_fields_W;               // The part of F_T_W from fields (springs, potentials, …). Unit: N.
  Vec3 p_WP;                     // Proxy point: the surface point of the deepest contact, else p_WT.
  std::uint32_t contact_count = 0;
  bool ramping = false;          // Some item is fading out (removed, or an old version of a change).
};

/// One tool's force: sums every contribution at port `port`'s tool position p_WT and velocity
/// v_WT, updates that port's contact state and energy meters (dt: the tick period, s), and adds
/// the reaction −F of each virtual mass it touches to the mass's accumulator without moving it
/// (advance_scene does, once every port has been evaluated). Each session's force budget applies
/// to this port's force alone. port < the scene's ports. Does not allocate.
SceneForce evaluate_scene_port(const CompiledScene& scene, std::uint32_t port, const Vec3& p_WT,
                               const Vec3& v_WT, std::int64_t tick, double dt = 1e-3);

/// What the scene's orientation fields ask of the tool at one tick.
struct SceneTorque {
  Vec3 tau_T_W;          // Torque on the tool, in W. Unit: N·m.
  bool ramping = false;  // Some orientation field is fading out.
};

/// One tool's torque: sums the orientation fields at port `port`'s orientation R_WT and angular
/// velocity w_WT (rad/s, in W), updating that port's spring filters and the fields' energy meters
/// (power τ·ω). Only where the scene has orientation fields (kStageOrientation) and the port's
/// device measures orientation; a scene without them does no orientation work at all. Torques
/// are outside the per-session force budget. Does not allocate.
SceneTorque evaluate_scene_orientation(const CompiledScene& scene, std::uint32_t port,
                                       const Quat& R_WT, const Vec3& w_WT, std::int64_t tick,
                                       double dt = 1e-3);

/// On the loop: virtual mass `contact` (an index into scene.contacts that is in scene.masses):
/// where its origin is and how fast it moves now (W; m, m/s).
struct MassNow {
  Vec3 p_WO;
  Vec3 v_WO;
};
MassNow mass_now(const CompiledScene& scene, std::uint32_t contact);
/// On the loop: adds F (N, W) to what moves virtual mass `contact` at the next advance_scene.
void push_mass(const CompiledScene& scene, std::uint32_t contact, const Vec3& F);
/// On the loop: puts virtual mass `contact` at p_WO (m, W) moving at v_WO (m/s), as the next
/// advance_scene starts it (a shared mass's copy taking the state of another site's).
void place_mass(const CompiledScene& scene, std::uint32_t contact, const Vec3& p_WO, const Vec3& v_WO);

/// Advances every virtual mass by dt under the reactions the ports accumulated this tick, held
/// over the tick (000 eq. 7.1, integrated exactly), clears the accumulators and publishes the
/// motion. Does not allocate.
void advance_scene(const CompiledScene& scene, double dt = 1e-3);

/// One tool, one tick: evaluate_scene_port for port 0, then advance_scene. Does not allocate.
/// Contact with a half-space: d = dot(point - p, n) > 0 is the penetration, F = (k d - b dot(v, n)) n
/// clamped so a wall only pushes (never pulls). Sphere: the same along the radial direction.
SceneForce evaluate_scene(const CompiledScene& scene, const Vec3& p_WT, const Vec3& v_WT,
                          std::int64_t tick, double dt = 1e-3);

/// Gain of an item whose fade began at fade_begin_tick, at tick `tick`: 1 before, then linear to 0.
double fade_gain(std::int64_t fade_begin_tick, std::int64_t tick, std::int64_t ramp_ticks);

/// Whether an item's force is (or is about to be) ramping out at `tick`: a removal or a newer
/// version has begun its fade and the fade has not yet reached zero. By tick alone, so a lockstep
/// run flags the same ticks however late the housekeeping drops the finished item.
inline bool is_fading_out(const ItemRamp& ramp, std::int64_t tick, std::int64_t ramp_ticks) {
  const auto unfinished = [&](std::int64_t begin) { return begin != kNeverTick && tick - begin < ramp_ticks; };
  if (unfinished(ramp.fade_begin_tick)) return true;
  for (const std::int64_t superseded : ramp.superseded_at) {
    if (unfinished(superseded)) return true;
  }
  return false;
}

/// Gain of an item at tick `tick`: its fade-in times its fade-outs (see ItemRamp).
double ramp_gain(const ItemRamp& ramp, std::int64_t tick, std::int64_t ramp_ticks);

}  // namespace haptic::engine
