/* The SDK's C API, version 1: a first part of haptic::Client (haptic/client.hpp) for programs and
 * languages that cannot load a C++ library. C99; opaque handles; structs that may grow start with
 * a `size` field the caller sets to sizeof (the *_init functions do).
 *
 * Errors: every function that can fail returns HAPTIC_OK (0) or a haptic_status code and, when
 * `err` is not NULL, fills it: the code and the SDK's message ("<call>: <field>: <problem>", as
 * in haptic/error.hpp) in a fixed buffer, truncated to fit and always NUL-terminated, so there is
 * nothing to free. On success `err` is set to HAPTIC_OK with an empty message. No C++ exception
 * crosses this boundary: each is caught and mapped to a code.
 *
 * Threads: a haptic_client may be used from one thread at a time (the caller's); the SDK runs its
 * own receive and heartbeat threads behind it, which call nothing of the caller's in this version.
 * haptic_client_poll_state blocks the calling thread for at most its timeout.
 *
 * Versioning, as the driver ABI (haptic/driver.h): HAPTIC_C_VERSION is the header's version and
 * haptic_c_version() the library's; a program compares them before calling anything else. */
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

/** Return codes: HAPTIC_OK, the SDK's error kinds (haptic::ErrorCode), and HAPTIC_TIMEOUT. */
typedef enum haptic_status {
  HAPTIC_OK = 0,
  HAPTIC_ERROR_CONNECTION = 1,          /* server unreachable or too slow */
  HAPTIC_ERROR_INVALID_ARGUMENT = 2,    /* a field was wrong; the message names it */
  HAPTIC_ERROR_NOT_FOUND = 3,           /* no such session or item */
  HAPTIC_ERROR_PERMISSION_DENIED = 4,   /* another client's item, or the token's role forbids it */
  HAPTIC_ERROR_RESOURCE_EXHAUSTED = 5,  /* a server limit */
  HAPTIC_ERROR_FAILED_PRECONDITION = 6, /* not possible in the server's state */
  HAPTIC_ERROR_VERSION_MISMATCH = 7,    /* client and server speak different API versions */
  HAPTIC_ERROR_INTERNAL = 8,            /* anything else */
  HAPTIC_ERROR_UNAUTHENTICATED = 9,     /* no token, or an unknown or expired one */
  HAPTIC_TIMEOUT = 100                  /* poll_state: no new sample in time (not an error) */
} haptic_status;

#define HAPTIC_ERROR_MESSAGE_SIZE 512

/** What went wrong: `code` as returned; `message` the SDK's text, truncated to fit. */
typedef struct haptic_error {
  int32_t code;
  char message[HAPTIC_ERROR_MESSAGE_SIZE];
} haptic_error;

typedef struct haptic_vec3 {
  double x, y, z;
} haptic_vec3;

/** The session; open with haptic_client_open, end with haptic_client_close. */
typedef struct haptic_client haptic_client;
/** An object registered by this client; removed (and freed) by haptic_object_remove. */
typedef struct haptic_object haptic_object;

/** How to reach hapticd (haptic::ClientConfig's fields so far). Strings are the caller's and are
 * copied by haptic_client_open. */
typedef struct haptic_client_config {
  uint32_t size;               /* sizeof(haptic_client_config) */
  const char* server_address;  /* gRPC "host:port" */
  const char* client_name;     /* 1..64 printable characters */
  const char* token;           /* bearer token; "" or NULL: none */
  uint32_t rpc_timeout_ms;     /* deadline of every control-plane call */
  uint32_t heartbeat_period_ms;
  uint32_t state_decimation;   /* state every n-th tick; 0: no state stream */
  uint32_t device_index;       /* the server's device port */
  int reconnect;               /* non-zero: reconnect on its own */
} haptic_client_config;

/** Fills `config` with haptic::ClientConfig's defaults and sets its size. */
void haptic_client_config_init(haptic_client_config* config);

/** Opens a session (Client's constructor). On success *out is the client; on failure *out is
 * NULL. Call from the thread that will use the client. */
int haptic_client_open(const haptic_client_config* config, haptic_client** out, haptic_error* err);
/** Ends the session and frees the client (NULL is ignored). Objects still held stay valid handles
 * that only need haptic_object_remove to be freed. Never from an SDK thread. */
void haptic_client_close(haptic_client* client);

/** A sample of the tool (haptic::State's fixed fields). Frames and units as in haptic/types.hpp. */
typedef struct haptic_state {
  uint32_t size;          /* sizeof(haptic_state), set by the caller */
  uint64_t tick;          /* server loop tick */
  uint64_t sequence;      /* datagram sequence; 0 from a step reply */
  double server_time;     /* Unit: s */
  haptic_vec3 position;   /* p_WT. Unit: m */
  haptic_vec3 velocity;   /* v_WT. Unit: m/s */
  haptic_vec3 force;      /* F_T_W commanded on the tool. Unit: N */
  haptic_vec3 proxy;      /* contact point. Unit: m */
  uint32_t contact_count;
  uint32_t flags;         /* haptic::StateFlag bits */
  uint32_t buttons;       /* bit i: button i */
} haptic_state;

/** Waits up to `timeout_ms` for a sample newer than the last one returned and copies the newest
 * into `out` (out->size must be at least sizeof(haptic_state) of version 1): HAPTIC_OK, or
 * HAPTIC_TIMEOUT with `out` untouched. Blocks the calling thread. */
int haptic_client_poll_state(haptic_client* client, haptic_state* out, uint32_t timeout_ms,
                             haptic_error* err);
/** Waits up to `timeout_ms` until a sample of tick >= `tick` has arrived, as poll_state. */
int haptic_client_wait_for_tick(haptic_client* client, uint64_t tick, haptic_state* out,
                                uint32_t timeout_ms, haptic_error* err);
/** Lockstep servers only: runs `ticks` ticks; *last_tick (if not NULL) is the last one's index. */
int haptic_client_step(haptic_client* client, uint32_t ticks, uint64_t* last_tick, haptic_error* err);

/** A plane the tool stays above (haptic::WallSpec). */
typedef struct haptic_wall_spec {
  uint32_t size;            /* sizeof(haptic_wall_spec) */
  haptic_vec3 point;        /* Unit: m */
  haptic_vec3 normal;       /* non-zero; the server normalises it */
  double stiffness;         /* Unit: N/m. Finite, >= 0 */
  double damping;           /* Unit: N·s/m. Finite, >= 0 */
  double static_friction;
  double dynamic_friction;
  int shared;               /* non-zero: any session may update it */
} haptic_wall_spec;

/** Fills `spec` with WallSpec's defaults (normal +z, no impedance) and sets its size. */
void haptic_wall_spec_init(haptic_wall_spec* spec);
/** Registers a wall; on success *out is its handle, on failure NULL (and nothing was made). */
int haptic_client_add_wall(haptic_client* client, const haptic_wall_spec* spec, haptic_object** out,
                           haptic_error* err);
/** Removes the object from the server (its force ramps out) and frees the handle, whatever the
 * result (NULL is ignored). */
int haptic_object_remove(haptic_object* object, haptic_error* err);

/** Sets the server's simulated operator to push the tool with a constant force (Unit: N, in W);
 * HAPTIC_ERROR_FAILED_PRECONDITION on real hardware. */
int haptic_client_set_operator_push(haptic_client* client, haptic_vec3 force, haptic_error* err);

#ifdef __cplusplus
}
#endif

#endif /* HAPTIC_HAPTIC_C_H */
