/* FROZEN: driver/include/haptic/driver.h as ABI version 1 released it, kept unchanged so the
 * tests can build a driver the way a lab built one then (tests/driver: ABI version 1 drivers must
 * still load). Do not edit; the current header is driver/include/haptic/driver.h.
 *
 * hapticd's device driver ABI, version 1: a device (real hardware, or a plant of one's own) in a
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
 */
#ifndef HAPTIC_DRIVER_H
#define HAPTIC_DRIVER_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define HAPTIC_DRIVER_ABI_VERSION 1u
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
} haptic_driver_reading;

/* The efforts to hold over the next tick. */
typedef struct haptic_driver_command {
  double tau[HAPTIC_DRIVER_MAX_JOINTS];   /* actuator efforts. Unit: N·m or N */
  double brake[HAPTIC_DRIVER_MAX_JOINTS]; /* brake effort limits, >= 0 (BRAKES). Unit: N·m or N */
} haptic_driver_command;

/* Device-clocked mode: hapticd's tick, called by the driver's servo loop once per cycle with the
 * cycle's time on CLOCK_MONOTONIC (ns). Returns nonzero when run_servo should return (hapticd is
 * stopping). */
typedef int (*haptic_driver_tick_fn)(void* context, int64_t monotonic_ns);

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
  /* Motors to zero, brakes on, at once; see the threads note above. */
  void (*enter_safe_state)(void* driver);

  /* Optional (NULL: server-clocked). Runs the vendor's servo loop on the calling thread, calling
   * tick once per cycle, until tick returns nonzero; returns HAPTIC_DRIVER_OK then, or
   * HAPTIC_DRIVER_FAILED if the servo loop could not run or ended on its own. */
  int (*run_servo)(void* driver, haptic_driver_tick_fn tick, void* context);
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
