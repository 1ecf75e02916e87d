/* The SDK's C API, version 1: haptic::Client (haptic/client.hpp) for programs and languages that
 * cannot load a C++ library (C, C#'s P/Invoke, MATLAB's loadlibrary, LabVIEW, Julia, Rust;
 * docs/c.md). C99; opaque handles; structs that may grow start with a `size` field the caller sets
 * to sizeof (the *_init functions do, with the C++ SDK's defaults). Library: libhaptic_c.so.1
 * (CMake: haptic::c from find_package(hapticd)).
 *
 * Units and frames as in haptic/types.hpp: SI units, positions, velocities and forces in the
 * device's world frame W. Booleans are int32_t: 0 false, anything else true.
 *
 * Errors: every function that can fail returns HAPTIC_OK (0) or a haptic_status code and, when
 * `err` is not NULL, fills it: the code and the SDK's message ("<call>: <field>: <problem>", as
 * in haptic/error.hpp) in a fixed buffer, truncated to fit and always NUL-terminated, so there is
 * nothing to free. On success `err` is set to HAPTIC_OK with an empty message. No C++ exception
 * crosses this boundary: each is caught and mapped to a code. A refused call changes nothing.
 *
 * Threads: a haptic_client may be called from any thread, as haptic::Client, except that
 * haptic_client_close must not race other calls on it. The callbacks (haptic_client_on_state,
 * _on_event, _on_connection) run on the SDK's own threads, not the caller's: keep them short,
 * guard what they share with locks, and do not call haptic_client_close or the same on_* setter
 * from inside one. The pointers a callback receives are valid only during the call.
 *
 * Versioning, as the driver ABI (haptic/driver.h): HAPTIC_C_VERSION is the header's version and
 * haptic_c_version() the library's; a program compares them before calling anything else. Within
 * a version, structs only grow at their end; a library reads a caller's struct up to its `size`
 * (a later library, whose struct has more fields, takes them as 0, "not given") and writes into it
 * no further than its `size`. So the *_init functions are macros in C: they pass the struct's size
 * as this header has it (haptic_wall_spec_init(&spec) is haptic_wall_spec_init_sized(&spec,
 * sizeof spec)); the functions of the same name, for languages that call the library without this
 * header (C#'s P/Invoke, MATLAB), fill version 1's fields and set version 1's size. */
#ifndef HAPTIC_HAPTIC_C_H
#define HAPTIC_HAPTIC_C_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define HAPTIC_C_VERSION 1u

/** The version of the C API the library was built with (HAPTIC_C_VERSION of its header). */
uint32_t haptic_c_version(void);

/* ---------------------------------------------------------------------------------------------
 * Errors */

/** Return codes: HAPTIC_OK, the SDK's error kinds (haptic::ErrorCode), and HAPTIC_TIMEOUT. */
typedef enum haptic_status {
  HAPTIC_OK = 0,
  HAPTIC_ERROR_CONNECTION = 1,          /* server unreachable or too slow */
  HAPTIC_ERROR_INVALID_ARGUMENT = 2,    /* a field was wrong; the message names it */
  HAPTIC_ERROR_NOT_FOUND = 3,           /* no such session or item */
  HAPTIC_ERROR_PERMISSION_DENIED = 4,   /* another client's item, or the token's role forbids it */
  HAPTIC_ERROR_RESOURCE_EXHAUSTED = 5,  /* a server limit */
  HAPTIC_ERROR_FAILED_PRECONDITION = 6, /* not possible in the server's (or the client's) state */
  HAPTIC_ERROR_VERSION_MISMATCH = 7,    /* client and server speak different API versions */
  HAPTIC_ERROR_INTERNAL = 8,            /* anything else */
  HAPTIC_ERROR_UNAUTHENTICATED = 9,     /* no token, or an unknown or expired one */
  HAPTIC_TIMEOUT = 100                  /* poll_state, wait_for_tick: no sample in time (not an error) */
} haptic_status;

#define HAPTIC_ERROR_MESSAGE_SIZE 512

/** What went wrong: `code` as returned; `message` the SDK's text, truncated to fit. */
typedef struct haptic_error {
  int32_t code;
  char message[HAPTIC_ERROR_MESSAGE_SIZE];
} haptic_error;

/* ---------------------------------------------------------------------------------------------
 * Value types (fixed within a version: they sit inside the structs that have a size) */

typedef struct haptic_vec3 {
  double x, y, z;
} haptic_vec3;

/** Unit quaternion (w, x, y, z); identity is {1, 0, 0, 0}. */
typedef struct haptic_quaternion {
  double w, x, y, z;
} haptic_quaternion;

/** Where an object is: its origin (Unit: m) and orientation in W. */
typedef struct haptic_pose {
  haptic_vec3 position;
  haptic_quaternion orientation;
} haptic_pose;

/** haptic::ImpedanceLaw: how penetration becomes force along a surface's normal. */
typedef enum haptic_impedance_law {
  HAPTIC_LAW_VELOCITY = 0,             /* K d − B v·n with the measured velocity (default) */
  HAPTIC_LAW_BACKWARD_DIFFERENCE = 1,  /* K d + B ḋ + M d̈ on the sampled penetration */
  HAPTIC_LAW_EXACT_ZOH = 2,            /* the exact zero-order-hold spring-damper (000 eq. 8.11) */
  HAPTIC_LAW_TUSTIN = 3                /* bilinear; refused with damping > 0 */
} haptic_impedance_law;

/** haptic::Impedance: a virtual spring-damper with optional Coulomb friction. */
typedef struct haptic_impedance {
  double stiffness;         /* Unit: N/m. Finite, >= 0 */
  double damping;           /* Unit: N·s/m. Finite, >= 0 */
  double static_friction;   /* μ_s >= 0 */
  double dynamic_friction;  /* 0 <= μ_d <= μ_s */
  double mass;              /* M of the discrete laws. Unit: kg */
  int32_t law;              /* haptic_impedance_law */
  int32_t transparency_optimal_damping;  /* the server chooses damping (StabilityReport) */
  int32_t virtual_coupling;              /* the server chooses a passive coupling */
} haptic_impedance;

/** haptic::Dynamics: mass > 0 makes an object a body the tool can push (000 eq. 7.1). */
typedef struct haptic_dynamics {
  double mass;     /* Unit: kg. 0: fixed */
  double damping;  /* viscous friction with the ground. Unit: N·s/m */
} haptic_dynamics;

/** haptic::Distance::Kind */
typedef enum haptic_distance_kind {
  HAPTIC_DISTANCE_POINT = 0,
  HAPTIC_DISTANCE_LINE = 1,
  HAPTIC_DISTANCE_PLANE = 2,
  HAPTIC_DISTANCE_SPHERE = 3
} haptic_distance_kind;

/** haptic::Distance: the distance function the fields are built on. */
typedef struct haptic_distance {
  int32_t kind;        /* haptic_distance_kind */
  haptic_vec3 origin;  /* Unit: m */
  haptic_vec3 axis;    /* LINE: direction; PLANE: normal */
  double radius;       /* SPHERE. Unit: m */
} haptic_distance;

/* ---------------------------------------------------------------------------------------------
 * Client */

/** The session; open with haptic_client_open, end with haptic_client_close. */
typedef struct haptic_client haptic_client;
/** An object registered by this client (walls, spheres, boxes, capsules, tangent planes, meshes). */
typedef struct haptic_object haptic_object;
/** An energy field registered by this client. */
typedef struct haptic_field haptic_field;

/** How to reach hapticd (haptic::ClientConfig). Strings are the caller's and are copied by
 * haptic_client_open; NULL is the same as "". */
typedef struct haptic_client_config {
  uint32_t size;                /* sizeof(haptic_client_config) */
  const char* server_address;   /* gRPC "host:port" */
  const char* client_name;      /* 1..64 printable characters */
  const char* token;            /* bearer token; "": none */
  const char* tls_ca_file;      /* PEM; non-empty: TLS (TlsOptions), "": plaintext */
  const char* tls_cert_file;    /* PEM: this client's certificate (mutual TLS) */
  const char* tls_key_file;     /* PEM: its key */
  const char* tls_server_name;  /* "": the host of server_address */
  const char* udp_address;      /* "host:port" to send datagrams to instead; "": the server's */
  uint32_t rpc_timeout_ms;      /* deadline of every control-plane call */
  uint32_t heartbeat_period_ms;
  uint32_t state_decimation;    /* state every n-th tick; 0: no state stream */
  uint32_t device_index;        /* the server's device port */
  int32_t reconnect;            /* reconnect on its own (haptic_client_on_connection tells) */
  int32_t allow_plaintext_token;
  uint32_t reconnect_backoff_min_ms;
  uint32_t reconnect_backoff_max_ms;
} haptic_client_config;

/** Fills `config` with haptic::ClientConfig's defaults and sets its size. */
void haptic_client_config_init(haptic_client_config* config);
void haptic_client_config_init_sized(haptic_client_config* config, uint32_t size);
#define haptic_client_config_init(config) haptic_client_config_init_sized((config), (uint32_t)sizeof(*(config)))

/** Opens a session (Client's constructor). On success *out is the client; on failure *out is NULL. */
int haptic_client_open(const haptic_client_config* config, haptic_client** out, haptic_error* err);
/** Ends the session (its objects and fields go with it) and frees the client; NULL is ignored.
 * The client is freed whatever the server answers, except from inside one of its own callbacks:
 * that is HAPTIC_ERROR_FAILED_PRECONDITION and the client stays open (call again from your own
 * thread). Objects and fields still held stay valid handles that only need removing to be freed. */
int haptic_client_close(haptic_client* client, haptic_error* err);

/** haptic::DeviceCapabilities as bits of haptic_device_info.capabilities. */
enum {
  HAPTIC_CAPABILITY_GRAVITY = 1u << 0,
  HAPTIC_CAPABILITY_BRAKES = 1u << 1,
  HAPTIC_CAPABILITY_FLEXIBLE_MODES = 1u << 2,
  HAPTIC_CAPABILITY_FRICTION = 1u << 3,
  HAPTIC_CAPABILITY_FORCE_SENSOR = 1u << 4,
  HAPTIC_CAPABILITY_QUANTIZED_POSITION = 1u << 5,
  HAPTIC_CAPABILITY_STATE_ESTIMATOR = 1u << 6,
  HAPTIC_CAPABILITY_DISTURBANCE_OBSERVER = 1u << 7,
  HAPTIC_CAPABILITY_ORIENTATION = 1u << 8,
  HAPTIC_CAPABILITY_TORQUE = 1u << 9
};

/** The device, as reported when the session opened (haptic::DeviceInfo). */
typedef struct haptic_device_info {
  uint32_t size;
  char name[128];
  char model[64];          /* "point_mass", "dc_motor_000", "five_bar_003", … */
  uint32_t capabilities;   /* HAPTIC_CAPABILITY_* bits */
  uint32_t dof;
  haptic_vec3 workspace_min;  /* Unit: m */
  haptic_vec3 workspace_max;  /* Unit: m */
  double max_force;        /* Unit: N */
  double loop_rate_hz;     /* Unit: Hz */
  double max_torque;       /* Unit: N·m */
  int32_t simulated;
  uint32_t buttons;        /* buttons reported in haptic_state.buttons */
} haptic_device_info;

int haptic_client_device_info(const haptic_client* client, haptic_device_info* out, haptic_error* err);
/** The session's id now (a reconnection after a server restart opens a new one). */
uint64_t haptic_client_session_id(const haptic_client* client);
/** How long the server keeps a silent session. Unit: ms. */
int64_t haptic_client_lease_timeout_ms(const haptic_client* client);

/* ---------------------------------------------------------------------------------------------
 * State */

/** Bits of haptic_state.flags (haptic::StateFlag). */
enum {
  HAPTIC_STATE_FORCE_SATURATED = 1u << 0,
  HAPTIC_STATE_FORCE_FAULT = 1u << 1,
  HAPTIC_STATE_RAMPING_OUT = 1u << 2,
  HAPTIC_STATE_DEVICE_FAULT = 1u << 3
};

/** A sample of the tool (haptic::State). Local times are steady-clock nanoseconds
 * (haptic_steady_clock_ns's clock). */
typedef struct haptic_state {
  uint32_t size;          /* sizeof(haptic_state), set by the caller */
  uint64_t tick;          /* server loop tick */
  uint64_t sequence;      /* datagram sequence; 0 from a step reply */
  double server_time;     /* Unit: s */
  haptic_vec3 position;   /* p_WT. Unit: m */
  haptic_vec3 velocity;   /* v_WT. Unit: m/s */
  haptic_vec3 force;      /* F_T_W commanded on the tool. Unit: N */
  haptic_vec3 proxy;      /* contact point; the position out of contact. Unit: m */
  uint32_t contact_count;
  uint32_t flags;         /* HAPTIC_STATE_* bits */
  uint32_t buttons;       /* bit i: button i */
  int32_t has_orientation;        /* the device measures the tool's orientation */
  haptic_quaternion orientation;  /* R_WT when has_orientation, else identity */
  haptic_vec3 torque;     /* tau_T_W commanded, when has_orientation, else 0. Unit: N·m */
  int64_t received_at_ns; /* local receipt time */
  int64_t arrived_at_ns;  /* the kernel's receive stamp; 0: none (a step reply) */
  int64_t age_ns;         /* queued this much longer than the quickest recent sample */
} haptic_state;

/** Waits up to `timeout_ms` for a sample newer than the last one returned and copies the newest
 * into `out` (out->size at least version 1's sizeof): HAPTIC_OK, or HAPTIC_TIMEOUT with `out`
 * untouched. Blocks the calling thread. */
int haptic_client_poll_state(haptic_client* client, haptic_state* out, uint32_t timeout_ms,
                             haptic_error* err);
/** Waits up to `timeout_ms` until a sample of tick >= `tick` has arrived, as poll_state. */
int haptic_client_wait_for_tick(haptic_client* client, uint64_t tick, haptic_state* out,
                                uint32_t timeout_ms, haptic_error* err);
/** Changes the state stream's decimation (every n-th tick; 0 stops it). */
int haptic_client_subscribe(haptic_client* client, uint32_t decimation, haptic_error* err);

/** Called with each newest State datagram, on the SDK's receive thread (Client::on_state). */
typedef void (*haptic_state_callback)(const haptic_state* state, void* user_data);
/** Sets the state callback (NULL stops it; returns once a call in progress has). `user_data` is
 * passed back untouched. */
int haptic_client_on_state(haptic_client* client, haptic_state_callback callback, void* user_data,
                           haptic_error* err);

/** The steady clock's now (ns), the clock of haptic_state's local times. */
int64_t haptic_steady_clock_ns(void);
/** The server's time (s) at local steady-clock time `local_ns`, from the clock offset and drift
 * (Client::server_time_at): 1 and *out set, or 0 before any sample. */
int32_t haptic_client_server_time_at(const haptic_client* client, int64_t local_ns, double* out);
/** Server clock − local steady clock (ns): 1 and *out set, or 0 before any sample. */
int32_t haptic_client_clock_offset_ns(const haptic_client* client, int64_t* out);
/** How much faster the server's clock runs (5e-5 is 50 ppm): 1, or 0 before two windows. */
int32_t haptic_client_clock_drift(const haptic_client* client, double* out);

/** The position at server time `t` between samples `a` and `b` by cubic Hermite interpolation
 * (haptic::interpolate_position; a frame's display time, from haptic_client_server_time_at). */
haptic_vec3 haptic_interpolate_position(const haptic_state* a, const haptic_state* b, double t);
/** The position at server time `t` after `latest`, extrapolated with the acceleration the two
 * newest samples imply (haptic::predict_position). */
haptic_vec3 haptic_predict_position(const haptic_state* previous, const haptic_state* latest,
                                    double t);

/** What the SDK's UDP receiver has seen (haptic::ReceiveCounters). */
typedef struct haptic_receive_counters {
  uint32_t size;
  uint64_t accepted;
  uint64_t rejected;
  uint64_t skipped;
  uint64_t challenges_answered;
  uint64_t callback_skipped;
  uint64_t lost;
  uint64_t reordered;
  uint64_t duplicates;
  uint64_t reconnects;
} haptic_receive_counters;

int haptic_client_receive_counters(const haptic_client* client, haptic_receive_counters* out,
                                   haptic_error* err);
/** Stops (0) or resumes heartbeats: stopping simulates a lost client. */
int haptic_client_set_heartbeats_enabled(haptic_client* client, int32_t enabled, haptic_error* err);

/* ---------------------------------------------------------------------------------------------
 * Objects and fields */

/** What a spec is (haptic_scene_item.kind, haptic_scene_entry.kind). */
typedef enum haptic_kind {
  HAPTIC_KIND_WALL = 1,
  HAPTIC_KIND_SPHERE = 2,
  HAPTIC_KIND_BOX = 3,
  HAPTIC_KIND_CAPSULE = 4,
  HAPTIC_KIND_TANGENT_PLANE = 5,
  HAPTIC_KIND_MESH = 6,
  HAPTIC_KIND_SPRING_FIELD = 101,
  HAPTIC_KIND_DISTANCE_SPRING = 102,
  HAPTIC_KIND_POTENTIAL_FIELD = 103,
  HAPTIC_KIND_LINEAR_FIELD = 104,
  HAPTIC_KIND_VISCOUS_FIELD = 105,
  HAPTIC_KIND_DETENT_FIELD = 106,
  HAPTIC_KIND_ORIENTATION_SPRING = 107,
  HAPTIC_KIND_ORIENTATION_DETENT = 108
} haptic_kind;

/** A plane the tool stays above: through `point`, outward `normal` (haptic::WallSpec). */
typedef struct haptic_wall_spec {
  uint32_t size;
  haptic_vec3 point;        /* Unit: m */
  haptic_vec3 normal;       /* non-zero; the server normalises it */
  haptic_impedance impedance;
  int32_t shared;           /* any session may update it; only its owner deletes it */
  int32_t across_sites;     /* shared with a federation's other sites */
} haptic_wall_spec;

/** A solid sphere (haptic::SphereSpec). */
typedef struct haptic_sphere_spec {
  uint32_t size;
  haptic_vec3 center;       /* Unit: m */
  double radius;            /* Unit: m. > 0 */
  haptic_impedance impedance;
  haptic_dynamics dynamics;
  int32_t shared;
  int32_t across_sites;
} haptic_sphere_spec;

/** A solid box centred on its pose (haptic::BoxSpec). */
typedef struct haptic_box_spec {
  uint32_t size;
  haptic_pose pose;
  haptic_vec3 half_extents; /* Unit: m. Each > 0 */
  haptic_impedance impedance;
  haptic_dynamics dynamics;
  int32_t shared;
  int32_t across_sites;
} haptic_box_spec;

/** A capsule along its pose's z axis (haptic::CapsuleSpec). */
typedef struct haptic_capsule_spec {
  uint32_t size;
  haptic_pose pose;
  double radius;            /* Unit: m. > 0 */
  double half_length;       /* Unit: m. >= 0 */
  haptic_impedance impedance;
  haptic_dynamics dynamics;
  int32_t shared;
  int32_t across_sites;
} haptic_capsule_spec;

/** Russo's tangent-plane local model (haptic::TangentPlaneSpec). */
typedef struct haptic_tangent_plane_spec {
  uint32_t size;
  haptic_pose pose;
  haptic_vec3 normal;       /* object frame */
  haptic_vec3 reference;    /* object frame. Unit: m */
  double tangential_stiffness;  /* Unit: N/m */
  double tangential_damping;    /* Unit: N·s/m */
  haptic_impedance impedance;
  int32_t across_sites;
} haptic_tangent_plane_spec;

/** A triangle mesh in its pose's frame (haptic::MeshSpec). The arrays are the caller's, read
 * during the call; in a read-back scene they belong to the scene until it is freed. */
typedef struct haptic_mesh_spec {
  uint32_t size;
  haptic_pose pose;
  const haptic_vec3* vertices;  /* Unit: m, object frame */
  uint32_t vertex_count;
  uint32_t index_count;         /* three per triangle */
  const uint32_t* indices;
  haptic_impedance impedance;
  int32_t shared;
  int32_t across_sites;
} haptic_mesh_spec;

/** F = −k (p − anchor) − b v, clipped to max_force if > 0 (haptic::SpringFieldSpec). */
typedef struct haptic_spring_field_spec {
  uint32_t size;
  haptic_vec3 anchor;       /* Unit: m */
  double stiffness;         /* Unit: N/m */
  double damping;           /* Unit: N·s/m */
  double max_force;         /* Unit: N. 0: no clip */
  int32_t across_sites;
} haptic_spring_field_spec;

/** A spring onto a point, line or plane (haptic::DistanceSpringSpec). */
typedef struct haptic_distance_spring_spec {
  uint32_t size;
  haptic_distance anchor;
  double stiffness;
  double damping;
  double max_force;
  int32_t across_sites;
} haptic_distance_spring_spec;

typedef enum haptic_potential_kind {
  HAPTIC_POTENTIAL_POLYNOMIAL = 0,
  HAPTIC_POTENTIAL_KHATIB = 1
} haptic_potential_kind;

/** F = −∇U over a distance (haptic::PotentialFieldSpec; Russo eqs. 5.6–5.7). */
typedef struct haptic_potential_field_spec {
  uint32_t size;
  haptic_distance distance;
  int32_t kind;                /* haptic_potential_kind */
  uint32_t order;              /* n, 2 … 8 */
  double gain;
  double offset;               /* c (polynomial). Unit: m */
  double influence_distance;   /* f0 (Khatib). Unit: m */
  double min_distance;         /* Unit: m */
  int32_t central_differences;
  int32_t across_sites;
} haptic_potential_field_spec;

/** F = F0 + K (p − origin) inside `radius`, fading over `fade_width` (haptic::LinearFieldSpec). */
typedef struct haptic_linear_field_spec {
  uint32_t size;
  haptic_vec3 origin;       /* Unit: m */
  haptic_vec3 force;        /* Unit: N */
  haptic_vec3 jacobian[3];  /* rows of K. Unit: N/m */
  double radius;            /* Unit: m */
  double fade_width;        /* Unit: m */
  int32_t across_sites;
} haptic_linear_field_spec;

/** F = −B v, everywhere (radius 0) or inside a sphere (haptic::ViscousFieldSpec). */
typedef struct haptic_viscous_field_spec {
  uint32_t size;
  double damping;           /* Unit: N·s/m */
  haptic_vec3 center;
  double radius;            /* Unit: m. 0: everywhere */
  double fade_width;        /* Unit: m */
  int32_t across_sites;
} haptic_viscous_field_spec;

/** A potential well with a repulsive rim (haptic::DetentFieldSpec). */
typedef struct haptic_detent_field_spec {
  uint32_t size;
  haptic_distance distance;
  double depth;             /* Unit: J */
  double radius;            /* Unit: m */
  double rim_height;        /* Unit: J */
  double rim_width;         /* Unit: m */
  int32_t across_sites;
} haptic_detent_field_spec;

/** A rotational spring-damper on the tool's orientation (haptic::OrientationSpringSpec). */
typedef struct haptic_orientation_spring_spec {
  uint32_t size;
  haptic_quaternion target; /* R_WG; the server normalises it */
  double stiffness;         /* Unit: N·m/rad */
  double damping;           /* Unit: N·m·s/rad */
  double max_torque;        /* Unit: N·m. 0: no clip */
  int32_t law;              /* haptic_impedance_law */
  int32_t across_sites;
} haptic_orientation_spring_spec;

/** A detent over the angle to `target` (haptic::OrientationDetentSpec). */
typedef struct haptic_orientation_detent_spec {
  uint32_t size;
  haptic_quaternion target;
  double depth;             /* Unit: J. > 0 */
  double radius;            /* Unit: rad */
  double rim_height;        /* Unit: J */
  double rim_width;         /* Unit: rad */
  double damping;           /* Unit: N·m·s/rad */
  int32_t across_sites;
} haptic_orientation_detent_spec;

/** Fill a spec with the C++ SDK's defaults and set its size. */
void haptic_wall_spec_init(haptic_wall_spec* spec);
void haptic_wall_spec_init_sized(haptic_wall_spec* spec, uint32_t size);
#define haptic_wall_spec_init(spec) haptic_wall_spec_init_sized((spec), (uint32_t)sizeof(*(spec)))
void haptic_sphere_spec_init(haptic_sphere_spec* spec);
void haptic_sphere_spec_init_sized(haptic_sphere_spec* spec, uint32_t size);
#define haptic_sphere_spec_init(spec) haptic_sphere_spec_init_sized((spec), (uint32_t)sizeof(*(spec)))
void haptic_box_spec_init(haptic_box_spec* spec);
void haptic_box_spec_init_sized(haptic_box_spec* spec, uint32_t size);
#define haptic_box_spec_init(spec) haptic_box_spec_init_sized((spec), (uint32_t)sizeof(*(spec)))
void haptic_capsule_spec_init(haptic_capsule_spec* spec);
void haptic_capsule_spec_init_sized(haptic_capsule_spec* spec, uint32_t size);
#define haptic_capsule_spec_init(spec) haptic_capsule_spec_init_sized((spec), (uint32_t)sizeof(*(spec)))
void haptic_tangent_plane_spec_init(haptic_tangent_plane_spec* spec);
void haptic_tangent_plane_spec_init_sized(haptic_tangent_plane_spec* spec, uint32_t size);
#define haptic_tangent_plane_spec_init(spec) haptic_tangent_plane_spec_init_sized((spec), (uint32_t)sizeof(*(spec)))
void haptic_mesh_spec_init(haptic_mesh_spec* spec);
void haptic_mesh_spec_init_sized(haptic_mesh_spec* spec, uint32_t size);
#define haptic_mesh_spec_init(spec) haptic_mesh_spec_init_sized((spec), (uint32_t)sizeof(*(spec)))
void haptic_spring_field_spec_init(haptic_spring_field_spec* spec);
void haptic_spring_field_spec_init_sized(haptic_spring_field_spec* spec, uint32_t size);
#define haptic_spring_field_spec_init(spec) haptic_spring_field_spec_init_sized((spec), (uint32_t)sizeof(*(spec)))
void haptic_distance_spring_spec_init(haptic_distance_spring_spec* spec);
void haptic_distance_spring_spec_init_sized(haptic_distance_spring_spec* spec, uint32_t size);
#define haptic_distance_spring_spec_init(spec) haptic_distance_spring_spec_init_sized((spec), (uint32_t)sizeof(*(spec)))
void haptic_potential_field_spec_init(haptic_potential_field_spec* spec);
void haptic_potential_field_spec_init_sized(haptic_potential_field_spec* spec, uint32_t size);
#define haptic_potential_field_spec_init(spec) haptic_potential_field_spec_init_sized((spec), (uint32_t)sizeof(*(spec)))
void haptic_linear_field_spec_init(haptic_linear_field_spec* spec);
void haptic_linear_field_spec_init_sized(haptic_linear_field_spec* spec, uint32_t size);
#define haptic_linear_field_spec_init(spec) haptic_linear_field_spec_init_sized((spec), (uint32_t)sizeof(*(spec)))
void haptic_viscous_field_spec_init(haptic_viscous_field_spec* spec);
void haptic_viscous_field_spec_init_sized(haptic_viscous_field_spec* spec, uint32_t size);
#define haptic_viscous_field_spec_init(spec) haptic_viscous_field_spec_init_sized((spec), (uint32_t)sizeof(*(spec)))
void haptic_detent_field_spec_init(haptic_detent_field_spec* spec);
void haptic_detent_field_spec_init_sized(haptic_detent_field_spec* spec, uint32_t size);
#define haptic_detent_field_spec_init(spec) haptic_detent_field_spec_init_sized((spec), (uint32_t)sizeof(*(spec)))
void haptic_orientation_spring_spec_init(haptic_orientation_spring_spec* spec);
void haptic_orientation_spring_spec_init_sized(haptic_orientation_spring_spec* spec, uint32_t size);
#define haptic_orientation_spring_spec_init(spec) haptic_orientation_spring_spec_init_sized((spec), (uint32_t)sizeof(*(spec)))
void haptic_orientation_detent_spec_init(haptic_orientation_detent_spec* spec);
void haptic_orientation_detent_spec_init_sized(haptic_orientation_detent_spec* spec, uint32_t size);
#define haptic_orientation_detent_spec_init(spec) haptic_orientation_detent_spec_init_sized((spec), (uint32_t)sizeof(*(spec)))

/** Register an object or field. On success *out is its handle; on failure NULL, and nothing was
 * made on the server (the message names the bad field: "CreateObject: object.radius: …"). */
int haptic_client_add_wall(haptic_client* client, const haptic_wall_spec* spec, haptic_object** out,
                           haptic_error* err);
int haptic_client_add_sphere(haptic_client* client, const haptic_sphere_spec* spec,
                             haptic_object** out, haptic_error* err);
int haptic_client_add_box(haptic_client* client, const haptic_box_spec* spec, haptic_object** out,
                          haptic_error* err);
int haptic_client_add_capsule(haptic_client* client, const haptic_capsule_spec* spec,
                              haptic_object** out, haptic_error* err);
int haptic_client_add_tangent_plane(haptic_client* client, const haptic_tangent_plane_spec* spec,
                                    haptic_object** out, haptic_error* err);
int haptic_client_add_mesh(haptic_client* client, const haptic_mesh_spec* spec, haptic_object** out,
                           haptic_error* err);
int haptic_client_add_spring_field(haptic_client* client, const haptic_spring_field_spec* spec,
                                   haptic_field** out, haptic_error* err);
int haptic_client_add_distance_spring(haptic_client* client, const haptic_distance_spring_spec* spec,
                                      haptic_field** out, haptic_error* err);
int haptic_client_add_potential_field(haptic_client* client, const haptic_potential_field_spec* spec,
                                      haptic_field** out, haptic_error* err);
int haptic_client_add_linear_field(haptic_client* client, const haptic_linear_field_spec* spec,
                                   haptic_field** out, haptic_error* err);
int haptic_client_add_viscous_field(haptic_client* client, const haptic_viscous_field_spec* spec,
                                    haptic_field** out, haptic_error* err);
int haptic_client_add_detent_field(haptic_client* client, const haptic_detent_field_spec* spec,
                                   haptic_field** out, haptic_error* err);
int haptic_client_add_orientation_spring(haptic_client* client,
                                         const haptic_orientation_spring_spec* spec,
                                         haptic_field** out, haptic_error* err);
int haptic_client_add_orientation_detent(haptic_client* client,
                                         const haptic_orientation_detent_spec* spec,
                                         haptic_field** out, haptic_error* err);

/** Replace an object or field with the one given, of any kind (ObjectHandle::update); refused,
 * the old one stays as it was. */
int haptic_object_update_wall(haptic_object* object, const haptic_wall_spec* spec, haptic_error* err);
int haptic_object_update_sphere(haptic_object* object, const haptic_sphere_spec* spec,
                                haptic_error* err);
int haptic_object_update_box(haptic_object* object, const haptic_box_spec* spec, haptic_error* err);
int haptic_object_update_capsule(haptic_object* object, const haptic_capsule_spec* spec,
                                 haptic_error* err);
int haptic_object_update_tangent_plane(haptic_object* object, const haptic_tangent_plane_spec* spec,
                                       haptic_error* err);
int haptic_object_update_mesh(haptic_object* object, const haptic_mesh_spec* spec, haptic_error* err);
int haptic_field_update_spring_field(haptic_field* field, const haptic_spring_field_spec* spec,
                                     haptic_error* err);
int haptic_field_update_distance_spring(haptic_field* field, const haptic_distance_spring_spec* spec,
                                        haptic_error* err);
int haptic_field_update_potential_field(haptic_field* field, const haptic_potential_field_spec* spec,
                                        haptic_error* err);
int haptic_field_update_linear_field(haptic_field* field, const haptic_linear_field_spec* spec,
                                     haptic_error* err);
int haptic_field_update_viscous_field(haptic_field* field, const haptic_viscous_field_spec* spec,
                                      haptic_error* err);
int haptic_field_update_detent_field(haptic_field* field, const haptic_detent_field_spec* spec,
                                     haptic_error* err);
int haptic_field_update_orientation_spring(haptic_field* field,
                                           const haptic_orientation_spring_spec* spec,
                                           haptic_error* err);
int haptic_field_update_orientation_detent(haptic_field* field,
                                           const haptic_orientation_detent_spec* spec,
                                           haptic_error* err);

/** The server's id of the item now (0 once it has gone). */
uint64_t haptic_object_id(const haptic_object* object);
uint64_t haptic_field_id(const haptic_field* field);
/** Removes the item from the server (its force ramps out) and frees the handle, whatever the
 * result (NULL is ignored). */
int haptic_object_remove(haptic_object* object, haptic_error* err);
int haptic_field_remove(haptic_field* field, haptic_error* err);
/** Frees the handle but leaves the item on the server until the session ends; returns its id. */
uint64_t haptic_object_release(haptic_object* object);
uint64_t haptic_field_release(haptic_field* field);

/** The server's stability report for an impedance (haptic::StabilityReport). */
typedef struct haptic_stability_report {
  uint32_t size;
  int32_t available;             /* 0: no report (a field other than an orientation spring) */
  double colgate_min_damping;    /* K T / 2 + |B|. Unit: N·s/m */
  double device_mass;            /* Unit: kg; 0 when the device gives no model */
  double device_damping;         /* Unit: N·s/m */
  double max_stable_stiffness;   /* Unit: N/m */
  double max_pole_magnitude;
  double chosen_damping;         /* Unit: N·s/m */
  double chosen_stiffness;       /* Unit: N/m */
  int32_t passive;
  int32_t device_known;
  int32_t stable;
  int32_t robustly_stable;       /* ‖L‖∞ ≤ 1 at chosen_damping (001 eq. 17) */
  char warning[256];             /* empty unless the contact is not expected to stay stable */
} haptic_stability_report;

int haptic_object_stability(const haptic_object* object, haptic_stability_report* out,
                            haptic_error* err);
int haptic_field_stability(const haptic_field* field, haptic_stability_report* out,
                           haptic_error* err);

/* ---------------------------------------------------------------------------------------------
 * Scenes */

/** One object or field of a scene: `spec` points to the struct `kind` names (its size set). */
typedef struct haptic_scene_item {
  int32_t kind;      /* haptic_kind */
  const void* spec;
} haptic_scene_item;

/** The handles of an applied scene, taken one by one. */
typedef struct haptic_applied_scene haptic_applied_scene;

/** Replaces this session's whole scene with `items` (objects and fields in any order; the server
 * numbers objects and fields each in the order given: "scene.objects[2]…"). All or nothing: if
 * anything is refused, nothing changes and *out is NULL. Handles from earlier calls go stale. */
int haptic_client_apply_scene(haptic_client* client, const haptic_scene_item* items, uint32_t count,
                              haptic_applied_scene** out, haptic_error* err);
/** The same from a scene file (protobuf JSON, as `hapticd --scene` reads). */
int haptic_client_apply_scene_file(haptic_client* client, const char* path,
                                   haptic_applied_scene** out, haptic_error* err);
void haptic_applied_scene_counts(const haptic_applied_scene* scene, uint32_t* objects,
                                 uint32_t* fields);
/** Moves the i-th object's (field's) handle to the caller; NULL when out of range or taken. */
haptic_object* haptic_applied_scene_take_object(haptic_applied_scene* scene, uint32_t index);
haptic_field* haptic_applied_scene_take_field(haptic_applied_scene* scene, uint32_t index);
/** The i-th object's stability report (Client::last_scene_stability). */
int haptic_applied_scene_stability(const haptic_applied_scene* scene, uint32_t index,
                                   haptic_stability_report* out, haptic_error* err);
/** Frees it; items whose handles were not taken stay on the server until the session ends. */
void haptic_applied_scene_free(haptic_applied_scene* scene);

/** `items` as a scene file (the JSON apply_scene_file reads; haptic::scene_json). Writes at most
 * `capacity` bytes with the terminating NUL into `buffer` (may be NULL with capacity 0) and sets
 * *length to the JSON's length without the NUL: call again with more room when it is >= capacity. */
int haptic_scene_json(const haptic_scene_item* items, uint32_t count, char* buffer, size_t capacity,
                      size_t* length, haptic_error* err);

/** A scene read back from the server (Client::scene). */
typedef struct haptic_registered_scene haptic_registered_scene;

/** What one read-back item is. */
typedef struct haptic_scene_entry {
  uint32_t size;
  int32_t kind;         /* haptic_kind: the struct to read its spec into */
  uint64_t id;
  uint64_t session_id;  /* 0: the server's own scene */
} haptic_scene_entry;

/** This session's items as the server holds them; with `all_sessions`, everyone's. */
int haptic_client_scene(haptic_client* client, int32_t all_sessions, haptic_registered_scene** out,
                        haptic_error* err);
void haptic_registered_scene_counts(const haptic_registered_scene* scene, uint32_t* objects,
                                    uint32_t* fields);
int haptic_registered_scene_object(const haptic_registered_scene* scene, uint32_t index,
                                   haptic_scene_entry* out, haptic_error* err);
int haptic_registered_scene_field(const haptic_registered_scene* scene, uint32_t index,
                                  haptic_scene_entry* out, haptic_error* err);
/** Copies the i-th object's (field's) spec into `spec`, the struct of its entry's kind with its
 * size set; a mesh's arrays point into the scene, valid until it is freed. */
int haptic_registered_scene_object_spec(const haptic_registered_scene* scene, uint32_t index,
                                        void* spec, haptic_error* err);
int haptic_registered_scene_field_spec(const haptic_registered_scene* scene, uint32_t index,
                                       void* spec, haptic_error* err);
void haptic_registered_scene_free(haptic_registered_scene* scene);

/** Work one item has exchanged with the device (haptic::ItemEnergy). */
typedef struct haptic_item_energy {
  uint64_t id;
  uint64_t session_id;
  int32_t is_object;
  double given_to_device;       /* Unit: J */
  double absorbed_from_device;  /* Unit: J */
} haptic_item_energy;

/** Where a virtual mass is (haptic::ObjectState). */
typedef struct haptic_object_state {
  uint64_t id;
  haptic_vec3 position;  /* Unit: m */
  haptic_vec3 velocity;  /* Unit: m/s */
} haptic_object_state;

/** Lists: at most `capacity` entries are written to `out` (may be NULL with capacity 0); *count is
 * how many there are. Ask again with more room when *count > capacity. */
int haptic_client_scene_energy(haptic_client* client, haptic_item_energy* out, uint32_t capacity,
                               uint32_t* count, haptic_error* err);
int haptic_client_object_states(haptic_client* client, haptic_object_state* out, uint32_t capacity,
                                uint32_t* count, haptic_error* err);

/* ---------------------------------------------------------------------------------------------
 * The simulated operator, lockstep time */

typedef enum haptic_operator_mode {
  HAPTIC_OPERATOR_RELEASE = 0,
  HAPTIC_OPERATOR_FOLLOW = 1,
  HAPTIC_OPERATOR_PUSH = 2
} haptic_operator_mode;
typedef enum haptic_grip {
  HAPTIC_GRIP_CUSTOM = 0,
  HAPTIC_GRIP_LOOSE = 1, /* 0.2 kg, 2 N/m, 3 N·s/m */
  HAPTIC_GRIP_TIGHT = 2  /* 2 kg, 800 N/m, 15 N·s/m */
} haptic_grip;
typedef enum haptic_path_shape {
  HAPTIC_PATH_FIXED = 0,
  HAPTIC_PATH_LINE = 1,
  HAPTIC_PATH_SINE = 2
} haptic_path_shape;
typedef enum haptic_profile_shape {
  HAPTIC_PROFILE_CONSTANT = 0,
  HAPTIC_PROFILE_STEP = 1,
  HAPTIC_PROFILE_RAMP = 2,
  HAPTIC_PROFILE_SINE = 3,
  HAPTIC_PROFILE_RECORDED = 4
} haptic_profile_shape;

/** What the server's simulated hand does (haptic::OperatorInput, its Path and Profile flattened). */
typedef struct haptic_operator_input {
  uint32_t size;
  int32_t mode;              /* haptic_operator_mode */
  haptic_vec3 target;        /* FOLLOW. Unit: m */
  double stiffness;          /* FOLLOW, custom grip. Unit: N/m */
  double damping;            /* Unit: N·s/m */
  double mass;               /* Unit: kg */
  int32_t grip;              /* haptic_grip */
  int32_t path_shape;        /* haptic_path_shape */
  haptic_vec3 path_end;      /* LINE. Unit: m */
  double path_duration_s;
  haptic_vec3 path_amplitude;  /* SINE. Unit: m */
  double path_frequency_hz;
  haptic_vec3 force;         /* PUSH: the force, the profile's amplitude. Unit: N */
  int32_t profile_shape;     /* haptic_profile_shape */
  int32_t profile_repeat;    /* RECORDED */
  double profile_start_s;
  double profile_rise_s;
  double profile_frequency_hz;
  haptic_vec3 profile_offset;
  const haptic_vec3* profile_samples;  /* RECORDED: at most 512, one every sample_period_s */
  uint32_t profile_sample_count;
  double profile_sample_period_s;
} haptic_operator_input;

/** Fills `input` with a release (OperatorInput's defaults) and sets its size. */
void haptic_operator_input_init(haptic_operator_input* input);
void haptic_operator_input_init_sized(haptic_operator_input* input, uint32_t size);
#define haptic_operator_input_init(input) haptic_operator_input_init_sized((input), (uint32_t)sizeof(*(input)))
/** Sets what the simulated hand does; HAPTIC_ERROR_FAILED_PRECONDITION on real hardware. */
int haptic_client_set_operator(haptic_client* client, const haptic_operator_input* input,
                               haptic_error* err);
/** The hand pushes with a constant force (OperatorInput::push). Unit: N, in W. */
int haptic_client_set_operator_push(haptic_client* client, haptic_vec3 force, haptic_error* err);
/** The hand pulls the tool towards `target` like a spring-damper (OperatorInput::follow). */
int haptic_client_set_operator_follow(haptic_client* client, haptic_vec3 target, double stiffness,
                                      double damping, haptic_error* err);

/** Lockstep servers only: runs `ticks` ticks; *last_tick (if not NULL) is the last one's index. */
int haptic_client_step(haptic_client* client, uint32_t ticks, uint64_t* last_tick, haptic_error* err);
/** Lockstep servers with simulated devices only: puts the server back as it started. */
int haptic_client_reset(haptic_client* client, haptic_error* err);

/* ---------------------------------------------------------------------------------------------
 * Events and the connection */

/** haptic::Event::Kind */
typedef enum haptic_event_kind {
  HAPTIC_EVENT_UNKNOWN = 0,
  HAPTIC_EVENT_SESSION_OPENED = 1,
  HAPTIC_EVENT_SESSION_CLOSED = 2,
  HAPTIC_EVENT_LEASE_EXPIRED = 3,
  HAPTIC_EVENT_SCENE_CHANGED = 4,
  HAPTIC_EVENT_FORCE_FAULT = 5,
  HAPTIC_EVENT_WATCH_STARTED = 6,
  HAPTIC_EVENT_DEVICE_FAULT = 7,
  HAPTIC_EVENT_RESET = 8
} haptic_event_kind;

/** Something that happened on the server (haptic::Event). */
typedef struct haptic_event {
  uint32_t size;
  int32_t kind;           /* haptic_event_kind */
  uint64_t session_id;    /* the session it concerns (0: the server's own) */
  uint64_t item_id;       /* SCENE_CHANGED for one item: its id */
  double server_time;     /* Unit: s */
  const char* message;    /* never NULL; valid during the callback only */
} haptic_event;

typedef void (*haptic_event_callback)(const haptic_event* event, void* user_data);
/** Calls `callback` on an SDK thread with each server event from now on, starting with
 * WATCH_STARTED (Client::on_event); NULL stops it. Refused as the server refuses the stream. */
int haptic_client_on_event(haptic_client* client, haptic_event_callback callback, void* user_data,
                           haptic_error* err);

/** haptic::ConnectionChange::State */
typedef enum haptic_connection_state {
  HAPTIC_CONNECTION_CONNECTED = 0,
  HAPTIC_CONNECTION_LOST = 1,
  HAPTIC_CONNECTION_RESUMED = 2,
  HAPTIC_CONNECTION_ENDED = 3
} haptic_connection_state;

/** A change of the connection (haptic::ConnectionChange). */
typedef struct haptic_connection_change {
  uint32_t size;
  int32_t state;                 /* haptic_connection_state */
  uint64_t session_id;
  int32_t new_session;
  uint32_t items_not_restored;
  int64_t outage_ms;
  const char* reason;            /* never NULL; valid during the callback only */
} haptic_connection_change;

typedef void (*haptic_connection_callback)(const haptic_connection_change* change, void* user_data);
/** Calls `callback` on the SDK's supervisor thread when the connection is lost and when it
 * resumes (Client::on_connection); NULL stops it. */
int haptic_client_on_connection(haptic_client* client, haptic_connection_callback callback,
                                void* user_data, haptic_error* err);
/** haptic_connection_state now. */
int32_t haptic_client_connection_state(const haptic_client* client);

/* ---------------------------------------------------------------------------------------------
 * Administration (with tokens on the server: an ADMIN token) */

/** haptic::Role */
typedef enum haptic_role {
  HAPTIC_ROLE_NONE = 0,
  HAPTIC_ROLE_OBSERVER = 1,
  HAPTIC_ROLE_CONTROLLER = 2,
  HAPTIC_ROLE_ADMIN = 3
} haptic_role;

/** One open session (haptic::SessionSummary). */
typedef struct haptic_session_summary {
  uint64_t session_id;
  char client_name[72];
  char peer[72];
  char token_name[72];
  uint32_t device_index;
  int32_t role;          /* haptic_role */
  double opened_time;    /* Unit: s */
} haptic_session_summary;

int haptic_client_sessions(haptic_client* client, haptic_session_summary* out, uint32_t capacity,
                           uint32_t* count, haptic_error* err);
/** Ends another session; `reason` (may be NULL) at most 256 characters. */
int haptic_client_kick_session(haptic_client* client, uint64_t session_id, const char* reason,
                               haptic_error* err);
/** A session id as people read it (16 hex digits and a NUL: 17 bytes). */
void haptic_session_id_text(uint64_t session_id, char out[17]);

/** One client's state stream (haptic::ClientStats). */
typedef struct haptic_stream_stats {
  uint64_t session_id;
  char client_name[72];
  char peer[72];
  uint32_t device_index;
  uint32_t decimation;
  uint64_t datagrams_sent;
  uint64_t heartbeats;
  uint64_t states_received;
  uint64_t states_lost;
  double last_heartbeat_age_s;
  uint32_t round_trip_samples;
  double round_trip_p50_us;
  double round_trip_p99_us;
  double round_trip_p999_us;
} haptic_stream_stats;

/** One coupling of a federation (haptic::CouplingStats). Unit: J. */
typedef struct haptic_coupling_stats {
  int32_t kind;              /* 0: tool, 1: shared mass */
  uint32_t port;
  uint64_t remote;
  uint64_t mass;
  double injected_j;
  double given_j;
  double sent_j;
  double received_j;
  double reservoir_j;
} haptic_coupling_stats;

/** The server's counters (haptic::Stats; its lists through haptic_client_stats's arrays). */
typedef struct haptic_stats {
  uint32_t size;
  uint32_t sessions;
  uint64_t ticks;
  double achieved_rate_hz;
  double lateness_p50_us;
  double lateness_p99_us;
  double lateness_p999_us;
  double lateness_max_us;
  uint64_t lateness_samples;
  double window_s;
  uint64_t overruns;
  uint32_t objects;
  uint32_t fields;
  uint64_t datagrams_sent;
  uint64_t datagrams_received;
  uint64_t datagrams_dropped;
  uint64_t force_faults;
  uint64_t force_saturations;
  uint64_t passivity_active_ticks;
  uint64_t leases_expired;
  uint64_t device_faults;
  double send_delay_p50_us;
  double send_delay_p99_us;
  double send_delay_p999_us;
  uint64_t heartbeats_rate_limited;
  uint64_t datagrams_foreign_source;
  uint64_t path_challenges_sent;
  uint64_t samples_skipped;
  uint64_t connections_refused;
  uint64_t connections_timed_out;
  uint64_t connections_evicted;
  uint64_t tls_handshakes_failed;
  uint32_t connections_open;
  uint32_t client_count;          /* entries of Stats::clients */
  int32_t has_federation;
  uint32_t coupling_count;        /* entries of FederationStats::couplings */
  uint64_t federation_samples_published;
  uint64_t federation_samples_failed;
  uint64_t federation_items_published;
  uint64_t federation_items_applied;
  uint64_t federation_items_refused;
  uint64_t federation_wrenches_accepted;
  uint64_t federation_wrenches_refused;
} haptic_stats;

/** The server's counters into `out`; the first `clients_capacity` clients and
 * `couplings_capacity` couplings into the arrays (either may be NULL with capacity 0). */
int haptic_client_stats(haptic_client* client, haptic_stats* out, haptic_stream_stats* clients,
                        uint32_t clients_capacity, haptic_coupling_stats* couplings,
                        uint32_t couplings_capacity, haptic_error* err);

/** A recording on the server (haptic::RecordingStatus). */
typedef struct haptic_recording_status {
  uint32_t size;
  char path[512];
  uint64_t start_tick;
  uint64_t samples;
  uint64_t samples_missed;
  uint64_t changes;
  uint64_t records_not_written;
  char write_error[256];
} haptic_recording_status;

/** Starts recording the run on the server into `name` in its recording_dir (out may be NULL). */
int haptic_client_start_recording(haptic_client* client, const char* name,
                                  haptic_recording_status* out, haptic_error* err);
int haptic_client_stop_recording(haptic_client* client, haptic_recording_status* out,
                                 haptic_error* err);

/* ---------------------------------------------------------------------------------------------
 * The session's samples in a file (haptic::Recorder; docs/recorder.md) */

/** Records what a client receives: every State it accepts, and the server's events and the
 * connection's changes, into CSV or HDF5, from a bounded queue a thread of its own drains. */
typedef struct haptic_recorder haptic_recorder;

typedef enum haptic_recorder_format {
  HAPTIC_RECORDER_AUTO = 0, /* by the path's extension: .csv, .h5 or .hdf5 */
  HAPTIC_RECORDER_CSV = 1,  /* samples in `path`, events in <stem>.events.csv */
  HAPTIC_RECORDER_HDF5 = 2  /* one file: /samples and /events, a dataset per column */
} haptic_recorder_format;

/** haptic::RecorderOptions. */
typedef struct haptic_recorder_options {
  uint32_t size;
  const char* path;         /* the file; copied */
  int32_t format;           /* haptic_recorder_format */
  int32_t events;           /* record the server's events and the connection's changes */
  int32_t overwrite;        /* replace an existing file instead of refusing it */
  uint64_t queue_capacity;  /* samples between the receive thread and the writer, >= 1 */
} haptic_recorder_options;

/** haptic::RecorderStats. */
typedef struct haptic_recorder_stats {
  uint32_t size;
  uint64_t samples_received;  /* States the client accepted while recording */
  uint64_t samples_written;   /* of those, the ones in the file */
  uint64_t dropped;           /* the ones that found the queue full */
  uint64_t events_written;
  uint64_t events_dropped;
  uint64_t write_errors;      /* samples and events a failed write kept from the file */
  char first_error[256];      /* the first failure's reason; empty if none */
} haptic_recorder_stats;

/** Fills `options` with RecorderOptions' defaults (no path) and sets its size. */
void haptic_recorder_options_init(haptic_recorder_options* options);
void haptic_recorder_options_init_sized(haptic_recorder_options* options, uint32_t size);
#define haptic_recorder_options_init(options) haptic_recorder_options_init_sized((options), (uint32_t)sizeof(*(options)))
/** Creates the file(s) and starts recording `client` (haptic::Recorder's constructor): on
 * success *out is the recorder; refused (a bad path, an existing file, capacity 0), *out is NULL,
 * the message names the field ("record: path: …") and no file is left behind. Several recorders
 * may record one client; none takes its callbacks. */
int haptic_client_record(haptic_client* client, const haptic_recorder_options* options,
                         haptic_recorder** out, haptic_error* err);
/** The totals so far (any thread). */
int haptic_recorder_get_stats(const haptic_recorder* recorder, haptic_recorder_stats* out,
                              haptic_error* err);
/** The samples' file and the events' file (empty without events); valid while the recorder is. */
const char* haptic_recorder_path(const haptic_recorder* recorder);
const char* haptic_recorder_events_path(const haptic_recorder* recorder);
/** Stops recording, writes what is queued, flushes and closes the file(s), frees the recorder and
 * puts the totals in `totals` (may be NULL). NULL is ignored. A failed write is in the totals, not
 * the return value. Close a recorder before its client to keep all it received. */
int haptic_recorder_close(haptic_recorder* recorder, haptic_recorder_stats* totals, haptic_error* err);

#ifdef __cplusplus
}
#endif

#endif /* HAPTIC_HAPTIC_C_H */
