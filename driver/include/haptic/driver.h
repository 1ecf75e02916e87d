/* hapticd's device driver ABI, version 2: a device (real hardware, or a plant of one's own) in a
 * shared library that hapticd loads at start ("driver": {"library": ..., "params": {...}} in its
 * configuration; docs/devices.md).
 *
 * Plain C (C99, C++ alike), independent of the SDK and of every other hapticd header. A driver
 * exports one symbol, haptic_driver_entry, returning a table of functions. hapticd checks the
 * table's abi_version and struct sizes before calling anything else and refuses a mismatch,
 * naming both versions.
 *
 * The device is described at its joints (like ros2_control's hardware interface): each tick the
 * driver reports joint positions and whatever else it senses, and applies joint efforts. Units are
 * SI: rad or m per joint; rad/s or m/s; N·m or N; N for forces in the device's world frame W.
 * Everything that needs a model of the device (kinematics, Jᵀ, gravity compensation, estimators)
 * is hapticd's, chosen by the configuration's "model".
 *
 * Threads. create, describe, start, stop and destroy are called off the loop. read, write and
 * enter_safe_state are called on the loop's time line: in server-clocked mode from one hapticd
 * thread, one call at a time, each expected to return within the configured call timeout (a read
 * or write that takes longer is a device fault: the loop goes on commanding nothing and the
 * device stays faulted); enter_safe_state may then be called from another thread while the late
 * call is still running, so it must be safe to call concurrently (set a flag, cut the
 * amplifiers). In device-clocked mode (run_servo set) the driver's own servo thread calls back
 * hapticd once per cycle and hapticd calls read and write from inside that callback.
 * No function may throw a C++ exception across this boundary.
 *
 * Versions. Version 2 only appends: fields at the end of haptic_driver_info, _reading and
 * _command, and functions at the end of haptic_driver_api. hapticd loads a version 1 driver as
 * before (it passes the same structs; a version 1 driver fills and reads their first part, which
 * is laid out as version 1 had it) and treats the version 2 fields as absent: no apparent mass or
 * damping (so no stability report or passivity on that port), no torque, no gripper.
 */
#ifndef HAPTIC_DRIVER_H
#define HAPTIC_DRIVER_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define HAPTIC_DRIVER_ABI_VERSION 2u
#define HAPTIC_DRIVER_ABI_VERSION_MIN 1u /* the oldest version hapticd still loads */
#define HAPTIC_DRIVER_MAX_JOINTS 6
#define HAPTIC_DRIVER_ERROR_SIZE 256

/* Return values of the functions below that report an outcome. */
#define HAPTIC_DRIVER_OK 0
#define HAPTIC_DRIVER_FAILED 1

/* haptic_driver_info.capabilities bits: what the device has. */
#define HAPTIC_DRIVER_MEASURED_RATES 0x01u /* q_dot comes from tachometers, not estimated */
#define HAPTIC_DRIVER_FORCE_SENSOR 0x02u   /* force_sensor_W is a handle load cell's */
#define HAPTIC_DRIVER_TORQUE_SENSORS 0x04u /* tau_sensor holds joint torque sensors' readings */
#define HAPTIC_DRIVER_BRAKES 0x08u         /* brake[] is applied */
#define HAPTIC_DRIVER_GRAVITY 0x10u        /* the plant carries a gravity load */
#define HAPTIC_DRIVER_ORIENTATION 0x20u    /* orientation_W is measured (a gimbal's encoders) */
/* ABI 2 on: */
#define HAPTIC_DRIVER_TORQUE_OUTPUT 0x40u  /* command.torque_W is applied (a 6-DOF device) */
#define HAPTIC_DRIVER_GRIPPER 0x80u        /* reading.gripper is measured; gripper_force applied */

/* Severity of a message a driver hands hapticd's log (set_log). */
#define HAPTIC_DRIVER_LOG_INFO 0
#define HAPTIC_DRIVER_LOG_WARNING 1
#define HAPTIC_DRIVER_LOG_ERROR 2

/* What the device is, filled in by describe(). */
typedef struct haptic_driver_info {
  char name[128];     /* for people: "Acme Falcon-3, serial 1234" (NUL-terminated) */
  uint32_t joints;    /* entries of q, q_dot, tau, brake in use: 1 ... HAPTIC_DRIVER_MAX_JOINTS */
  uint32_t dof;       /* degrees of freedom of the tool point: 1 ... 3 */
  uint32_t buttons;   /* buttons reported in haptic_driver_reading.buttons: 0 ... 32 */
  uint32_t capabilities;      /* HAPTIC_DRIVER_* bits */
  double max_force;           /* largest force at the tool the loop may command, > 0. Unit: N */
  double workspace_min[3];    /* the tool point's reachable box in W. Unit: m */
  double workspace_max[3];
  /* Device-clocked drivers: the rate run_servo calls back at. Unit: Hz. 0 for server-clocked. */
  double servo_rate_hz;

  /* ABI 2 on (a version 1 driver leaves these 0). The device at its tool point, per axis of W,
   * as a mass-damper: what hapticd's stability report and passivity controller model the port
   * by (it takes the smallest of the three axes). 0: unknown, and both are off on the port. From
   * the vendor's data or an identification; the values at the workspace's centre where they vary.
   * Units: kg, N·s/m. */
  double apparent_mass[3];
  double apparent_damping[3];
  /* TORQUE_OUTPUT: the largest torque at the tool the loop may command, > 0 (N·m); and the
   * rotation about each axis of W as an inertia-damper (kg·m², N·m·s/rad; 0: unknown). */
  double max_torque;
  double apparent_inertia[3];
  double apparent_rotational_damping[3];
  /* GRIPPER: the largest gripping force, > 0 (N), and the opening's range (rad or m). */
  double gripper_max_force;
  double gripper_min;
  double gripper_max;
} haptic_driver_info;

/* One sample of the device's sensors. */
typedef struct haptic_driver_reading {
  double q[HAPTIC_DRIVER_MAX_JOINTS];          /* joint positions. Unit: rad or m */
  double q_dot[HAPTIC_DRIVER_MAX_JOINTS];      /* joint rates (MEASURED_RATES), else 0 */
  double tau_sensor[HAPTIC_DRIVER_MAX_JOINTS]; /* operator's joint torques (TORQUE_SENSORS) */
  double force_sensor_W[3];                    /* operator's force on the handle (FORCE_SENSOR) */
  /* The tool's orientation in W as a unit quaternion (w, x, y, z) (ORIENTATION); normalized by
   * hapticd, and a norm far from 1 (outside 0.5 ... 2) is a fault. Ignored without the bit. */
  double orientation_W[4];
  uint32_t buttons;                            /* bit i: button i pressed */
  uint32_t safe_state;                         /* nonzero: the device holds its own safe state */
  /* Increases with every new sample the device takes. A reading whose sequence has not moved for
   * the configured number of ticks is stale: a device fault. */
  uint64_t sequence;

  /* ABI 2 on. The tool's angular velocity in W (ORIENTATION with MEASURED_RATES; else 0, and
   * hapticd differentiates the orientation). Unit: rad/s. */
  double angular_velocity_W[3];
  /* GRIPPER: the opening and its rate. Units: rad or m; rad/s or m/s. */
  double gripper;
  double gripper_rate;
} haptic_driver_reading;

/* The efforts to hold over the next tick. */
typedef struct haptic_driver_command {
  double tau[HAPTIC_DRIVER_MAX_JOINTS];   /* actuator efforts. Unit: N·m or N */
  double brake[HAPTIC_DRIVER_MAX_JOINTS]; /* brake effort limits, >= 0 (BRAKES). Unit: N·m or N */

  /* ABI 2 on. TORQUE_OUTPUT: the torque about the tool point in W, within max_torque (else 0).
   * Unit: N·m. GRIPPER: the force closing the gripper, within gripper_max_force. Unit: N. */
  double torque_W[3];
  double gripper_force;
} haptic_driver_command;

/* Device-clocked mode: hapticd's tick, called by the driver's servo loop once per cycle with the
 * cycle's time on CLOCK_MONOTONIC (ns). Returns nonzero when run_servo should return (hapticd is
 * stopping). */
typedef int (*haptic_driver_tick_fn)(void* context, int64_t monotonic_ns);

/* ABI 2 on: hapticd's log, for what a person at the device must know (calibration needed, a
 * vendor warning). level: HAPTIC_DRIVER_LOG_*. Callable from any of the driver's threads but
 * not from read or write (it may allocate). */
typedef void (*haptic_driver_log_fn)(void* context, int level, const char* message);

typedef struct haptic_driver_api {
  uint32_t abi_version;          /* HAPTIC_DRIVER_ABI_VERSION the driver was built against */
  uint32_t info_size;            /* sizeof(haptic_driver_info) as the driver was compiled */
  uint32_t reading_size;         /* sizeof(haptic_driver_reading) */
  uint32_t command_size;         /* sizeof(haptic_driver_command) */

  /* Opens the device. params_json: the configuration's "params" object as JSON ("{}" when
   * absent). Returns the driver's handle, or NULL with a NUL-terminated reason in error
   * (HAPTIC_DRIVER_ERROR_SIZE bytes) naming what was wrong. */
  void* (*create)(const char* params_json, char* error);
  void (*destroy)(void* driver);
  int (*describe)(void* driver, haptic_driver_info* info);
  /* Before the first tick / after the last. */
  int (*start)(void* driver);
  void (*stop)(void* driver);

  int (*read)(void* driver, haptic_driver_reading* reading);
  /* dt: the tick the command is held over. Unit: s. */
  int (*write)(void* driver, const haptic_driver_command* command, double dt);
  /* Motors to zero, brakes on, at once; see the threads note above. The device stays so until
   * the next write. A write after enter_safe_state is hapticd commanding the device again (it writes
   * a zero command right after entering the safe state, and forces only after a good reading): the
   * driver applies it as any write, or, where the device must leave its safe state in its own way
   * first (forces turned on again only with the hand slow), keeps the motors at zero, reports
   * safe_state in each reading until the device has left it, and applies the commands written from
   * then on. Such a write returns HAPTIC_DRIVER_OK: a device still safe is not a failed call. A write
   * already running when enter_safe_state is called (a late one, beside hapticd's watchdog) must not
   * end the safe state: its command is dropped or held at zero until the next write. */
  void (*enter_safe_state)(void* driver);

  /* Optional (NULL: server-clocked). Runs the vendor's servo loop on the calling thread, calling
   * tick once per cycle, until tick returns nonzero; returns HAPTIC_DRIVER_OK then, or
   * HAPTIC_DRIVER_FAILED if the servo loop could not run or ended on its own. */
  int (*run_servo)(void* driver, haptic_driver_tick_fn tick, void* context);

  /* ABI 2 on; each may be NULL. */
  /* Before start(): where the driver's messages go, until destroy(). */
  void (*set_log)(void* driver, haptic_driver_log_fn log, void* context);
  /* For `hapticd --list-devices`, without create(): the devices this driver can open on this
   * host. Writes NUL-terminated text of at most size bytes into list, one device a line: the
   * params (JSON) that open it, a tab, a description for people. Returns how many devices it
   * found, or -1 with the reason in list when it cannot ask (the vendor's runtime is missing:
   * say what to install). params_json: the configuration's params, "{}" when none. */
  int (*list_devices)(const char* params_json, char* list, size_t size);
  /* Why the most recent read, write or start failed, for hapticd's DEVICE_FAULT event and log
   * ("the device was unplugged (USB)", the vendor's error text): NUL-terminated, at most
   * HAPTIC_DRIVER_ERROR_SIZE bytes into error; "" when nothing failed. Called off the loop while
   * read and write may run on another thread: keep what it reads in atomics or fixed strings. */
  void (*last_error)(void* driver, char* error);
} haptic_driver_api;

/* The one symbol a driver library exports (visible even when the library hides the rest). */
#if defined(__GNUC__)
#define HAPTIC_DRIVER_EXPORT __attribute__((visibility("default")))
#else
#define HAPTIC_DRIVER_EXPORT
#endif
HAPTIC_DRIVER_EXPORT const haptic_driver_api* haptic_driver_entry(void);
typedef const haptic_driver_api* (*haptic_driver_entry_fn)(void);
#define HAPTIC_DRIVER_ENTRY_SYMBOL "haptic_driver_entry"

#ifdef __cplusplus
}
#endif

#endif /* HAPTIC_DRIVER_H */
