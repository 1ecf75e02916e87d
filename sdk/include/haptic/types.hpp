#pragma once
// Value types of the hapticd SDK. SI units throughout; positions, velocities and forces are in the
// device's world frame W (see docs/architecture.md).

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace haptic {

struct Vec3 {
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
  friend bool operator==(const Vec3&, const Vec3&) = default;
};

/// Unit quaternion (w, x, y, z); the default is identity.
struct Quaternion {
  double w = 1.0;
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
  friend bool operator==(const Quaternion&, const Quaternion&) = default;
};

/// How penetration becomes force along a surface's normal (docs/scene.md).
enum class ImpedanceLaw {
  kVelocity,            ///< K d − B v·n with the device's measured velocity (the default)
  kBackwardDifference,  ///< K d + B ḋ + M d̈ on the sampled penetration
  kExactZoh,            ///< the exact zero-order-hold spring-damper (000 eq. 8.11)
  kTustin,              ///< bilinear; the server refuses it with damping > 0 (unstable)
};

/// A virtual spring-damper, with optional Coulomb friction (kVelocity law only).
struct Impedance {
  double stiffness = 0.0;  ///< Unit: N/m. Finite, >= 0.
  double damping = 0.0;    ///< Unit: N·s/m. Finite, >= 0.
  double static_friction = 0.0;   ///< μ_s >= 0.
  double dynamic_friction = 0.0;  ///< 0 <= μ_d <= μ_s.
  ImpedanceLaw law = ImpedanceLaw::kVelocity;
  double mass = 0.0;       ///< M of the discrete laws. Unit: kg.
  /// Let the server replace `damping` by Eom et al.'s transparency-optimal value for this
  /// stiffness on its device (reported in StabilityReport::chosen_damping).
  bool transparency_optimal_damping = false;
  /// Let the server replace stiffness and damping by a virtual coupling that is passive on its
  /// device (Colgate et al. 1995; soft on a lightly damped device; reported in the StabilityReport).
  bool virtual_coupling = false;
  friend bool operator==(const Impedance&, const Impedance&) = default;
};

/// Where an object is: its origin and orientation in W.
struct Pose {
  Vec3 position{};          ///< Unit: m.
  Quaternion orientation{};
  friend bool operator==(const Pose&, const Pose&) = default;
};

/// A half-space wall: the plane through `point` with outward `normal`; the solid lies behind it.
struct WallSpec {
  Vec3 point{};             ///< Unit: m.
  Vec3 normal{0, 0, 1};     ///< Non-zero; the server normalises it.
  Impedance impedance{};
  bool shared = false;      ///< any session may update it; only its owner deletes it
  bool across_sites = false;  ///< shared with the other sites of a federation; refused by a server not in one
  friend bool operator==(const WallSpec&, const WallSpec&) = default;
};

/// A virtual mass the tool can push (000 eq. 7.1): m Ẍ + B Ẋ = f. mass 0: the object is fixed.
struct Dynamics {
  double mass = 0.0;        ///< Unit: kg.
  double damping = 0.0;     ///< B, viscous friction with the ground. Unit: N·s/m.
  friend bool operator==(const Dynamics&, const Dynamics&) = default;
};

/// A solid sphere the tool is pushed out of.
struct SphereSpec {
  Vec3 center{};            ///< Unit: m.
  double radius = 0.0;      ///< Unit: m. > 0.
  Impedance impedance{};
  Dynamics dynamics{};      ///< mass > 0: the sphere can be pushed around
  bool shared = false;      ///< any session may update it; only its owner deletes it
  bool across_sites = false;  ///< shared with the other sites of a federation; refused by a server not in one
  friend bool operator==(const SphereSpec&, const SphereSpec&) = default;
};

/// A spring pulling the tool to `anchor`: F = −k (p − anchor) − b v, clipped to max_force if > 0.
struct SpringFieldSpec {
  Vec3 anchor{};            ///< Unit: m.
  double stiffness = 0.0;   ///< Unit: N/m.
  double damping = 0.0;     ///< Unit: N·s/m.
  double max_force = 0.0;   ///< Unit: N. 0: no clip.
  bool across_sites = false;  ///< shared with the other sites of a federation; refused by a server not in one
  friend bool operator==(const SpringFieldSpec&, const SpringFieldSpec&) = default;
};

/// A solid box centred on its pose, faces normal to the pose's axes.
struct BoxSpec {
  Pose pose{};
  Vec3 half_extents{};      ///< Unit: m. Each > 0.
  Impedance impedance{};
  Dynamics dynamics{};      ///< mass > 0: the box can be pushed around
  bool shared = false;      ///< any session may update it; only its owner deletes it
  bool across_sites = false;  ///< shared with the other sites of a federation; refused by a server not in one
  friend bool operator==(const BoxSpec&, const BoxSpec&) = default;
};

/// A solid capsule along its pose's z axis: radius around the segment ±half_length.
struct CapsuleSpec {
  Pose pose{};
  double radius = 0.0;       ///< Unit: m. > 0.
  double half_length = 0.0;  ///< Unit: m. >= 0.
  Impedance impedance{};
  Dynamics dynamics{};
  bool shared = false;      ///< any session may update it; only its owner deletes it
  bool across_sites = false;  ///< shared with the other sites of a federation; refused by a server not in one
  friend bool operator==(const CapsuleSpec&, const CapsuleSpec&) = default;
};

/// A triangle mesh in its pose's frame, rendered with a god object (thin parts hold).
struct MeshSpec {
  Pose pose{};
  std::vector<Vec3> vertices;          ///< Unit: m, in the object frame.
  std::vector<std::uint32_t> indices;  ///< Three per triangle.
  Impedance impedance{};
  bool shared = false;      ///< any session may update it; only its owner deletes it
  bool across_sites = false;  ///< shared with the other sites of a federation; refused by a server not in one
  friend bool operator==(const MeshSpec&, const MeshSpec&) = default;
};

/// Russo's tangent-plane local model: the plane through the pose position with outward `normal`
/// (object frame), the impedance along the normal behind it, and a tangential spring-damper that
/// pulls the tool towards `reference` within the plane. For a slow host that sends the surface
/// nearest the tool a few tens of times a second (update() it; the change cross-fades).
struct TangentPlaneSpec {
  Pose pose{};
  Vec3 normal{0, 0, 1};
  Vec3 reference{};                  ///< Object frame. Unit: m.
  double tangential_stiffness = 0.0; ///< Unit: N/m.
  double tangential_damping = 0.0;   ///< Unit: N·s/m.
  Impedance impedance{};
  bool across_sites = false;  ///< shared with the other sites of a federation; refused by a server not in one
  friend bool operator==(const TangentPlaneSpec&, const TangentPlaneSpec&) = default;
};

/// A distance function the fields are built on.
struct Distance {
  enum class Kind { kPoint, kLine, kPlane, kSphere };
  Kind kind = Kind::kPoint;
  Vec3 origin{};            ///< Unit: m.
  Vec3 axis{0, 0, 1};       ///< kLine: direction; kPlane: normal.
  double radius = 0.0;      ///< kSphere. Unit: m.
  friend bool operator==(const Distance&, const Distance&) = default;
};

/// A spring onto a point, line or plane (the zero set of `anchor`).
struct DistanceSpringSpec {
  Distance anchor{};
  double stiffness = 0.0;   ///< Unit: N/m.
  double damping = 0.0;     ///< Unit: N·s/m.
  double max_force = 0.0;   ///< Unit: N. 0: no clip.
  bool across_sites = false;  ///< shared with the other sites of a federation; refused by a server not in one
  friend bool operator==(const DistanceSpringSpec&, const DistanceSpringSpec&) = default;
};

/// F = −∇U over a distance f: polynomial (1/n) K (c − f)ⁿ where f < c, or Khatib
/// (1/n) K (1/f − 1/f0)ⁿ where f < f0 (Russo eqs. 5.6–5.7).
struct PotentialFieldSpec {
  enum class Kind { kPolynomial, kKhatib };
  Distance distance{};
  Kind kind = Kind::kPolynomial;
  std::uint32_t order = 2;          ///< n, 2 … 8.
  double gain = 0.0;
  double offset = 0.0;              ///< c (polynomial). Unit: m.
  double influence_distance = 0.0;  ///< f0 (Khatib). Unit: m.
  double min_distance = 0.0;        ///< Khatib's force is capped below this. Unit: m.
  bool central_differences = false; ///< gradient by central differences instead of analytic
  bool across_sites = false;  ///< shared with the other sites of a federation; refused by a server not in one
  friend bool operator==(const PotentialFieldSpec&, const PotentialFieldSpec&) = default;
};

/// F = F0 + K (p − origin) inside `radius`, fading (C¹) to zero over the outer `fade_width`.
struct LinearFieldSpec {
  Vec3 origin{};            ///< Unit: m.
  Vec3 force{};             ///< Unit: N.
  Vec3 jacobian[3]{};       ///< Rows of K. Unit: N/m.
  double radius = 0.0;      ///< Unit: m.
  double fade_width = 0.0;  ///< Unit: m.
  bool across_sites = false;  ///< shared with the other sites of a federation; refused by a server not in one
  friend bool operator==(const LinearFieldSpec&, const LinearFieldSpec&) = default;
};

/// F = −B v, everywhere (radius 0) or inside a sphere with a fade.
struct ViscousFieldSpec {
  double damping = 0.0;     ///< Unit: N·s/m.
  Vec3 center{};
  double radius = 0.0;      ///< Unit: m. 0: everywhere.
  double fade_width = 0.0;  ///< Unit: m.
  bool across_sites = false;  ///< shared with the other sites of a federation; refused by a server not in one
  friend bool operator==(const ViscousFieldSpec&, const ViscousFieldSpec&) = default;
};

/// A potential well with a repulsive rim around the zero set of `distance`.
struct DetentFieldSpec {
  Distance distance{};
  double depth = 0.0;       ///< Unit: J.
  double radius = 0.0;      ///< Unit: m.
  double rim_height = 0.0;  ///< Unit: J.
  double rim_width = 0.0;   ///< Unit: m.
  bool across_sites = false;  ///< shared with the other sites of a federation; refused by a server not in one
  friend bool operator==(const DetentFieldSpec&, const DetentFieldSpec&) = default;
};

/// A rotational spring-damper on the tool's orientation R_WT, for a device that measures one
/// (DeviceCapabilities::orientation): the torque tau = −K θ − B ω pulls it towards `target`, θ the
/// rotation vector from the target to the tool's orientation (rad, in W) and ω the tool's angular
/// velocity (rad/s, in W). The torque reaches the hand on a device that takes torques
/// (docs/scene.md, "Orientation fields").
struct OrientationSpringSpec {
  Quaternion target{};      ///< R_WG, the orientation pulled towards; the server normalises it.
  double stiffness = 0.0;   ///< K. Unit: N·m/rad. Finite, >= 0.
  double damping = 0.0;     ///< B. Unit: N·m·s/rad. Finite, >= 0.
  double max_torque = 0.0;  ///< |tau| is clipped to this. Unit: N·m. 0: no clip.
  /// How K and B are discretized, as for a contact's Impedance (kVelocity: the measured ω).
  ImpedanceLaw law = ImpedanceLaw::kVelocity;
  bool across_sites = false;  ///< shared with the other sites of a federation; refused by a server not in one
  friend bool operator==(const OrientationSpringSpec&, const OrientationSpringSpec&) = default;
};

/// DetentFieldSpec's well and rim over the angle ρ = |θ| (rad) between the tool's orientation and
/// `target`: the handle clicks into the target orientation. For a device that measures the
/// orientation; the torque (in W) reaches the hand on a device that takes torques.
struct OrientationDetentSpec {
  Quaternion target{};      ///< R_WG, the orientation of the well; the server normalises it.
  double depth = 0.0;       ///< Unit: J. > 0.
  double radius = 0.0;      ///< Of the well. Unit: rad. > 0; radius + rim_width <= π.
  double rim_height = 0.0;  ///< Unit: J. >= 0.
  double rim_width = 0.0;   ///< Unit: rad. > 0 when rim_height > 0.
  double damping = 0.0;     ///< On ω inside radius + rim_width. Unit: N·m·s/rad. Finite, >= 0.
  bool across_sites = false;  ///< shared with the other sites of a federation; refused by a server not in one
  friend bool operator==(const OrientationDetentSpec&, const OrientationDetentSpec&) = default;
};

/// Bits of State::flags.
enum StateFlag : std::uint32_t {
  kForceSaturated = 1u << 0,  ///< the server's force limits cut the scene's force
  kForceFault = 1u << 1,      ///< a non-finite force was replaced by zero
  kRampingOut = 1u << 2,      ///< some force is ramping to zero (removed objects, shutdown)
  kDeviceFault = 1u << 3,     ///< the device's reading failed or was not finite; zero commanded
};

/// One tick's sample as the server streamed it.
struct State {
  std::uint64_t tick = 0;        ///< Server loop tick.
  /// The subscription's number for this due sample, from 1 (every due sample takes one): a gap
  /// is a sample that never reached this client (ReceiveCounters::lost); 0 from a Step reply.
  std::uint64_t sequence = 0;
  double server_time = 0.0;      ///< Server time of the tick. Unit: s.
  Vec3 position;                 ///< Tool position p_WT. Unit: m.
  Vec3 velocity;                 ///< Tool velocity v_WT. Unit: m/s.
  Vec3 force;                    ///< Force commanded on the tool F_T_W. Unit: N.
  Vec3 proxy;                    ///< Contact (proxy) point; equals position out of contact. Unit: m.
  std::uint32_t contact_count = 0;
  std::uint32_t flags = 0;       ///< StateFlag bits.
  std::uint32_t buttons = 0;     ///< The device's buttons, bit i for button i (DeviceInfo::buttons).
  /// The tool's orientation R_WT, for a device that measures one (capabilities.orientation).
  std::optional<Quaternion> orientation;
  /// Torque commanded on the tool tau_T_W, after the server's safety stage, in W; present exactly
  /// when `orientation` is (zero on a device that takes no torque, or with no orientation field).
  /// Unit: N·m.
  std::optional<Vec3> torque;
  std::chrono::steady_clock::time_point received_at;  ///< Local receipt time.
  /// When the datagram reached this host's socket, by the kernel's receive stamp (SO_TIMESTAMPNS)
  /// on steady_clock: received_at − arrived_at is the time the receiving thread took to run.
  /// Empty where the kernel gives no stamp, and for a sample from a Step reply.
  std::optional<std::chrono::steady_clock::time_point> arrived_at;
  /// At receipt: how much longer this sample took to arrive than the quickest recent one
  /// (receipt − stamp + clock_offset): the time it spent queued anywhere. 0 from a Step reply.
  std::chrono::nanoseconds age{0};
};

/// Something that happened on the server, as WatchEvents reports it (Client::on_event).
struct Event {
  enum class Kind {
    kUnknown,
    kSessionOpened,
    kSessionClosed,
    kLeaseExpired,
    kSceneChanged,
    kForceFault,    ///< non-finite forces were replaced by zero
    kWatchStarted,  ///< the first event of every stream: later events will arrive
    kDeviceFault,   ///< the device's reading failed or was not finite; zero force commanded
    kReset,         ///< a lockstep reset: ticks count from 1 again, the scene is as it started
  };
  Kind kind = Kind::kUnknown;
  std::uint64_t session_id = 0;  ///< The session it concerns (0: the server's own).
  double server_time = 0.0;      ///< Unit: s.
  /// kSceneChanged: "object 3 created" / "updated" / "deleted" (or "field …"), one event per item;
  /// a whole scene applied at once: "N objects, M fields".
  std::string message;
  std::uint64_t item_id = 0;     ///< kSceneChanged for one item: its id; else 0.
};

/// A change of a Client's connection (Client::on_connection).
struct ConnectionChange {
  enum class State {
    kConnected,  ///< as opened (never announced: the state before any change)
    kLost,       ///< the server stopped answering, or no longer knows the session
    kResumed,    ///< answering again; see new_session
    /// the server ended the session for good (an admin's KickSession, or its token expired):
    /// the client does not reconnect; reason says why
    kEnded,
  };
  State state = State::kConnected;
  /// The session now: after a server restart, a new one (Client::session_id() changes with it).
  std::uint64_t session_id = 0;
  /// kResumed: the session had gone (the server restarted, or its lease ran out), so a new one
  /// was opened, every item the client held registered again (their handles keep working; id()
  /// gives the new ids), and the state stream and event watch resumed.
  bool new_session = false;
  /// kResumed with new_session: items the new session refused (their handles' calls then throw
  /// NotFoundError saying why).
  std::uint32_t items_not_restored = 0;
  std::string reason;  ///< kLost: what failed. kResumed: how long the outage lasted.
  std::chrono::milliseconds outage{0};  ///< kResumed: from the loss to the resumption
};

/// What a server's bearer token lets its holder do (ClientConfig::token; docs/deployment.md).
enum class Role {
  kNone,        ///< the server has no tokens
  kObserver,    ///< sessions, state, events, reading the device and the scene
  kController,  ///< also changing the scene, the simulated operator, lockstep steps
  kAdmin,       ///< also statistics, every session, ending one
};

/// A recording on the server (Client::start_recording, stop_recording).
struct RecordingStatus {
  std::string path;                 ///< on the server
  std::uint64_t start_tick = 0;     ///< ticks completed when it began; 0: hapticd --replay reproduces it
  std::uint64_t samples = 0;        ///< stop: samples written
  std::uint64_t samples_missed = 0; ///< stop: samples the recorder could not read in time
  std::uint64_t changes = 0;        ///< stop: changes written
  /// stop: records that never reached the file because a write failed (a full disk); 0 when the
  /// file is whole. The file then ends before them and replays up to its last whole record.
  std::uint64_t records_not_written = 0;
  std::string write_error;          ///< stop: the first failed write's reason; empty if none
};

/// A session id as people read it: 16 lower-case hex digits, as the server's log, its events and
/// hapticctl write it (`kick` takes it back).
std::string session_id_text(std::uint64_t session_id);

/// One open session, as an admin sees it (Client::sessions; session_id_text to print its id).
struct SessionSummary {
  std::uint64_t session_id = 0;
  std::string client_name;
  std::uint32_t device_index = 0;
  std::string peer;        ///< the host it was opened from
  std::string token_name;  ///< the token it was opened with; empty without tokens
  Role role = Role::kNone;
  double opened_time = 0.0;  ///< server time at its opening. Unit: s.
};

/// What a device has (the server computes only those terms).
struct DeviceCapabilities {
  bool gravity = false;               ///< A gravity load the device compensates.
  bool brakes = false;                ///< Brakes beside the motors.
  bool flexible_modes = false;        ///< Simulated structural modes.
  bool friction = false;              ///< Joint or transmission friction.
  bool force_sensor = false;          ///< A measured interaction force.
  bool quantized_position = false;    ///< Positions from encoder counts.
  bool state_estimator = false;       ///< Velocities from an observer.
  bool disturbance_observer = false;  ///< Axes shaped to a nominal mass-damper.
  bool orientation = false;           ///< The tool's orientation is measured (State::orientation).
  bool torque = false;                ///< The handle takes torques (orientation fields; State::torque).
};

struct DeviceInfo {
  std::string name;
  std::string model;         ///< "point_mass", "dc_motor_000", "five_bar_003", …
  DeviceCapabilities capabilities;
  std::uint32_t dof = 0;
  Vec3 workspace_min;        ///< Unit: m.
  Vec3 workspace_max;        ///< Unit: m.
  double max_force = 0.0;    ///< Unit: N.
  double loop_rate_hz = 0.0; ///< Unit: Hz.
  bool simulated = false;
  std::uint32_t buttons = 0; ///< Buttons reported in State::buttons.
  double max_torque = 0.0;   ///< Unit: N·m (capabilities.torque).
};

/// What the server can say about an object's impedance on its device (docs/scene.md): Colgate's
/// passivity bound and, where the device gives a mass-damper model, the sampled stability margin.
struct StabilityReport {
  double colgate_min_damping = 0.0;   ///< K T / 2 + |B|. Unit: N·s/m.
  double device_mass = 0.0;           ///< 0 when the device gives no model. Unit: kg.
  double device_damping = 0.0;        ///< Unit: N·s/m.
  bool passive = false;               ///< device_damping > colgate_min_damping
  bool device_known = false;
  bool stable = false;                ///< the sampled loop in contact is stable (known devices)
  double max_stable_stiffness = 0.0;  ///< Unit: N/m.
  double max_pole_magnitude = 0.0;
  double chosen_damping = 0.0;        ///< with transparency_optimal_damping or virtual_coupling. Unit: N·s/m.
  double chosen_stiffness = 0.0;      ///< with virtual_coupling. Unit: N/m.
  bool robustly_stable = false;       ///< ‖L‖∞ ≤ 1 at chosen_damping (001 eq. 17)
  /// Empty unless the server accepted the object but expects its contact not to stay stable on
  /// this device (stable false); says why (the server logs it too).
  std::string warning;
};

/// Where a virtual mass has been pushed to.
struct ObjectState {
  std::uint64_t id = 0;
  Vec3 position{};   ///< Its origin in W. Unit: m.
  Vec3 velocity{};   ///< Unit: m/s.
};

/// Work one object or field has exchanged with the device since it was registered.
struct ItemEnergy {
  std::uint64_t id = 0;
  std::uint64_t session_id = 0;       ///< 0: the server's own scene
  bool is_object = false;
  double given_to_device = 0.0;       ///< Unit: J.
  double absorbed_from_device = 0.0;  ///< Unit: J.
};

/// The server's counters (GetStats).
/// One client's state stream in Stats: what the server sent it, and what its heartbeats report
/// of what arrived.
struct ClientStats {
  std::uint64_t session_id = 0;
  std::string client_name;
  std::string peer;                   ///< the host it was opened from
  std::uint32_t device_index = 0;
  std::uint32_t decimation = 0;       ///< its subscription (every n-th tick); 0: none
  std::uint64_t datagrams_sent = 0;   ///< State datagrams sent to it
  std::uint64_t heartbeats = 0;       ///< heartbeats accepted from it
  std::uint64_t states_received = 0;  ///< as its last heartbeat reported
  std::uint64_t states_lost = 0;      ///< as its last heartbeat reported (sequence gaps)
  std::uint32_t ack_window = 0;       ///< lockstep flow control granted (datagrams); 0: none
  std::uint64_t acknowledged_sequence = 0;  ///< the highest sequence it has acknowledged
  /// Samples due to it numbered but never sent (skipped, overwritten, refused by the kernel):
  /// states_received + states_lost <= datagrams_sent + samples_unsent.
  std::uint64_t samples_unsent = 0;
  double last_heartbeat_age_s = -1.0;  ///< how long ago its last heartbeat came; -1: none yet
  /// Round trip from a tick's stamp to the client and back (send delay + network both ways), over
  /// its last 256 heartbeats; real time only. Unit: µs.
  std::uint32_t round_trip_samples = 0;
  double round_trip_p50_us = 0.0;
  double round_trip_p99_us = 0.0;
  double round_trip_p999_us = 0.0;
};

/// One coupling across the network of a federation (docs/federation.md, "The passivity layer"):
/// its network passivity layer's books at this site, cumulative since it began. Unit: J.
struct CouplingStats {
  enum class Kind {
    kTool,  ///< this site's tool at `port` and another site's tool (`remote`)
    kMass,  ///< this site's copy of shared mass `mass` and another site's copy (`remote`: its site)
  };
  Kind kind = Kind::kTool;
  std::uint32_t port = 0;    ///< kTool: this site's device port
  std::uint64_t remote = 0;  ///< kTool: the remote tool's key; kMass: the other site's key
  std::uint64_t mass = 0;    ///< kMass: the mass's key
  double injected_j = 0.0;   ///< put into the coupling by this site's user (or copy)
  double given_j = 0.0;      ///< given to this site's user (or copy)
  double sent_j = 0.0;       ///< sent to the other site
  double received_j = 0.0;   ///< received from it
  double reservoir_j = 0.0;  ///< held here now: injected − given + received − sent
};

/// What crossed between the sites of a federation (docs/federation.md).
struct FederationStats {
  std::uint64_t samples_published = 0;  ///< tool and mass-copy samples this site published
  std::uint64_t samples_failed = 0;     ///< publications DDS refused
  std::uint64_t items_published = 0;    ///< versions of this site's across_sites items sent
  std::uint64_t items_applied = 0;      ///< other sites' item versions applied here
  std::uint64_t items_refused = 0;      ///< refused by this site's checks
  std::uint64_t wrenches_accepted = 0;  ///< ROS 2 wrenches taken in
  std::uint64_t wrenches_refused = 0;   ///< refused (frame, NaN)
  /// Other sites' tool and mass samples refused (another site's name, NaN, from a site cut off).
  std::uint64_t samples_refused = 0;
  double energy_refused_j = 0.0;        ///< energy other sites claimed, not credited (over the cap). J
  std::uint64_t sites_cut_off = 0;      ///< sites cut off: their energy books did not add up
  std::vector<CouplingStats> couplings;
};

struct Stats {
  std::uint64_t ticks = 0;
  double achieved_rate_hz = 0.0;
  /// The loop's wake-up lateness over the last window_s seconds (a sliding window).
  double lateness_p50_us = 0.0;
  double lateness_p99_us = 0.0;
  double lateness_max_us = 0.0;
  double lateness_p999_us = 0.0;
  std::uint64_t lateness_samples = 0;  ///< ticks in the window
  double window_s = 0.0;               ///< of the lateness and send-delay figures. Unit: s.
  std::uint64_t overruns = 0;
  std::uint32_t sessions = 0;
  std::uint32_t objects = 0;
  std::uint32_t fields = 0;
  std::uint64_t datagrams_sent = 0;
  std::uint64_t datagrams_received = 0;
  std::uint64_t datagrams_dropped = 0;
  std::uint64_t force_faults = 0;
  std::uint64_t force_saturations = 0;
  std::uint64_t passivity_active_ticks = 0;  ///< ticks the passivity controller added damping
  std::uint64_t leases_expired = 0;
  std::uint64_t device_faults = 0;
  double send_delay_p50_us = 0.0;  ///< real time: tick stamp to its first datagram sent
  double send_delay_p99_us = 0.0;
  double send_delay_p999_us = 0.0;
  std::uint64_t heartbeats_rate_limited = 0;   ///< of datagrams_dropped: over a session's budget
  std::uint64_t datagrams_foreign_source = 0;  ///< of datagrams_dropped: from another host
  std::uint64_t path_challenges_sent = 0;      ///< to UDP addresses not yet proven to receive
  std::uint64_t samples_skipped = 0;  ///< not sent: a newer one was ready (the sender fell behind)
  /// Due samples the loop's ring had overwritten before the sender read them.
  std::uint64_t samples_missed = 0;
  /// Lockstep flow-controlled streams sent on without waiting: nothing acknowledged for 1 s.
  std::uint64_t ack_stalls = 0;
  std::uint32_t connections_open = 0;     ///< control-plane connections held now
  std::uint64_t connections_refused = 0;  ///< over a connection cap, or no descriptor left
  /// Accepted, then closed: no TLS handshake or HTTP/2 preface within handshake_timeout_ms.
  std::uint64_t connections_timed_out = 0;
  /// Accepted, then closed at max_connections to make room for a host holding fewer.
  std::uint64_t connections_evicted = 0;
  std::uint64_t tls_handshakes_failed = 0;  ///< no or a wrong client certificate, not TLS, ...
  std::vector<ClientStats> clients;  ///< every open session, in id order
  std::optional<FederationStats> federation;  ///< with a federation section (docs/federation.md)
};

/// What the server's simulated operator (a hand holding the tool) does. Profiles and trajectories
/// run from the moment the input reaches the server's loop.
struct OperatorInput {
  enum class Mode { kRelease, kFollow, kPush };
  /// Grip presets for kFollow: the ends of a human grip's range.
  enum class Grip {
    kCustom,  ///< mass, stiffness and damping as given
    kLoose,   ///< 0.2 kg, 2 N/m, 3 N·s/m
    kTight,   ///< 2 kg, 800 N/m, 15 N·s/m
  };
  /// How the target moves from `target` (kFollow).
  struct Path {
    enum class Shape { kFixed, kLine, kSine };
    Shape shape = Shape::kFixed;
    Vec3 end{};                 ///< kLine: to here over duration_s, then holds. Unit: m.
    double duration_s = 0.0;    ///< Unit: s.
    Vec3 amplitude{};           ///< kSine: target + amplitude sin(2π f t). Unit: m.
    double frequency_hz = 0.0;  ///< Unit: Hz.
  };
  /// How the pushing force changes over time (kPush); `force` is its amplitude (except kRecorded).
  struct Profile {
    enum class Shape { kConstant, kStep, kRamp, kSine, kRecorded };
    Shape shape = Shape::kConstant;
    double start_s = 0.0;       ///< kStep, kRamp: when it begins. Unit: s.
    double rise_s = 0.0;        ///< kRamp: rise time. Unit: s.
    double frequency_hz = 0.0;  ///< kSine: offset + force sin(2π f t). Unit: Hz.
    Vec3 offset{};              ///< kSine. Unit: N.
    /// kRecorded: forces one every `sample_period_s` (at most 512), linearly interpolated; after
    /// the last the force holds it, or wraps round when `repeat`. Unit: N, in W.
    std::vector<Vec3> samples;
    double sample_period_s = 0.0;  ///< kRecorded. Unit: s.
    bool repeat = false;           ///< kRecorded.
  };

  Mode mode = Mode::kRelease;
  Vec3 target{};           ///< kFollow: where the hand pulls the tool (the path's start). Unit: m.
  double stiffness = 0.0;  ///< kFollow, kCustom grip: hand stiffness. Unit: N/m.
  double damping = 0.0;    ///< kFollow, kCustom grip: hand damping. Unit: N·s/m.
  double mass = 0.0;       ///< kFollow, kCustom grip: hand mass moving with the tool. Unit: kg.
  Grip grip = Grip::kCustom;
  Path path{};
  Vec3 force{};            ///< kPush: the force (the profile's amplitude). Unit: N.
  Profile profile{};

  /// The hand pulls the tool towards `target` like a spring-damper.
  static OperatorInput follow(Vec3 target, double stiffness, double damping) {
    OperatorInput input;
    input.mode = Mode::kFollow;
    input.target = target;
    input.stiffness = stiffness;
    input.damping = damping;
    return input;
  }
  /// A loose or tight grip whose target moves from `from` to `to` in `duration_s`.
  static OperatorInput follow_line(Vec3 from, Vec3 to, double duration_s, Grip grip) {
    OperatorInput input;
    input.mode = Mode::kFollow;
    input.target = from;
    input.grip = grip;
    input.path.shape = Path::Shape::kLine;
    input.path.end = to;
    input.path.duration_s = duration_s;
    return input;
  }
  /// The hand pushes with a constant force.
  static OperatorInput push(Vec3 force) {
    OperatorInput input;
    input.mode = Mode::kPush;
    input.force = force;
    return input;
  }
  /// The hand pushes with a force that follows `profile`.
  static OperatorInput push(Vec3 force, Profile profile) {
    OperatorInput input = push(force);
    input.profile = profile;
    return input;
  }
  /// The hand pushes with a recorded force: `samples` one every `sample_period_s` seconds.
  static OperatorInput push_recorded(std::vector<Vec3> samples, double sample_period_s,
                                     bool repeat = false) {
    OperatorInput input;
    input.mode = Mode::kPush;
    input.profile.shape = Profile::Shape::kRecorded;
    input.profile.samples = std::move(samples);
    input.profile.sample_period_s = sample_period_s;
    input.profile.repeat = repeat;
    return input;
  }
  /// The hand lets go.
  static OperatorInput release() { return OperatorInput{}; }
};

/// What the SDK's UDP receiver has seen.
struct ReceiveCounters {
  std::uint64_t accepted = 0;  ///< State datagrams decoded and authenticated.
  std::uint64_t rejected = 0;  ///< Datagrams dropped: malformed, wrong session, bad tag.
  /// Accepted States never handed out: a newer one had arrived by the time the receive thread
  /// read them (it hands out only the newest of what has queued up), the callback_skipped ones
  /// apart.
  std::uint64_t skipped = 0;
  /// Path challenges answered: the server asks each new UDP address to prove it receives before
  /// it sends state there.
  std::uint64_t challenges_answered = 0;
  /// States the on_state callback never saw because they arrived (by the kernel's receive stamp)
  /// while it was still busy with an older one; it is always handed the newest.
  std::uint64_t callback_skipped = 0;
  /// States due to this client that never arrived: gaps in each session's sequence (net of late
  /// arrivals), since the server numbers every due sample, whether the network lost it or the
  /// server's sender skipped it (real time, fallen behind: Stats::samples_skipped) or found it
  /// overwritten (Stats::samples_missed); plus, for each outage the client reconnected after,
  /// the samples the stream would have carried meanwhile (its length × loop rate ÷ decimation:
  /// an estimate).
  std::uint64_t lost = 0;
  /// States that arrived after a newer one (reordered on the way); not counted as lost.
  std::uint64_t reordered = 0;
  /// States that arrived a second time (duplicated on the way, within the last 64 sequence
  /// numbers): dropped, neither accepted nor handed out.
  std::uint64_t duplicates = 0;
  /// Times the connection was lost and resumed (Client::on_connection).
  std::uint64_t reconnects = 0;
};

}  // namespace haptic
