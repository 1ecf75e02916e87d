#pragma once
// haptic-lab's `run`: one scene — a hapticd configuration (device ports, operator, objects,
// fields, rate, integrators) — run in lockstep time, in-process, through the same TickRunner as
// the server's loop, with a trace of every tick. The base every study is built on, and the way
// to reproduce any figure.

#include <array>
#include <cstdint>
#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include "haptic/v1/config.pb.h"
#include "runtime/tick_runner.hpp"
#include "runtime/tick_sample.hpp"

namespace haptic::lab {

struct RunSummary {
  std::uint64_t ticks = 0;          // Ticks run (fewer than asked when the callback stopped the run).
  double energy_to_device = 0.0;    // Work the scene's force (and torque) did on the tool. Unit: J.
  double energy_from_device = 0.0;  // Work the tool did against it. Unit: J.
  std::uint64_t fault_ticks = 0;    // Ticks with a force or device fault flag.
  /// Every published state, and every device's joint state, was finite (the loop publishes the
  /// last good reading when a plant's state has become non-finite; its joints show it).
  bool finite = true;
  /// Paced in real time (DeviceTime::real_time): ticks that started more than half a period late.
  std::uint64_t late_ticks = 0;
};

/// A simulated device's joint state: the plant's true state (not what its sensors measure), at
/// the instant the tick's reading was taken (the tick's start, time_ns). Per device:
///   point mass (3): its Cartesian axes x, y, z (m) and their rates (m/s) — the same as p_WT, v_WT;
///   000 DC motor (1): the load angle θ_L = r θ_m (rad, eq. 3.1a) and θ̇_L (rad/s);
///   001 parallel device (2): the motor angles q_1, q_2 (rad) and rates (rad/s) of its Cartesian
///       state through the leg constraints;
///   003 five-bar (3): q0 (horizontal, base), q1 (axial), q2 (vertical) (rad) and rates (rad/s);
///   004 joystick (3): the gimbal angles θ, Φ (rad) and the shaft's load-side length R (m, the
///       handle side of the cable), and their rates (rad/s, rad/s, m/s).
struct JointState {
  std::uint32_t count = 0;        // Joints reported, 0 … 3 (0: a device without a joint model).
  std::array<double, 3> q{};      // Unit: rad or m, per joint (above).
  std::array<double, 3> q_dot{};  // Unit: rad/s or m/s.
};

/// One port's tick as simulate_scene reports it.
struct TickRecord {
  std::uint32_t port = 0;
  std::uint64_t ticks = 0;           // Ticks the run will take in all (the sample's tick counts to it).
  runtime::TickSample sample;        // What the loop published (tick from 1, time = (tick − 1) T).
  double energy_to_device_j = 0.0;   // Work the scene's force has done on the tool so far. Unit: J.
  double energy_from_device_j = 0.0; // Work the tool has done against it so far. Unit: J.
  JointState joints;                 // The device's joint state at the sample's time.
};

/// Called once per tick and port, in order; returning false stops the run after this tick.
using TickCallback = std::function<bool(const TickRecord&)>;

/// Called once before the run with the loop's ports as the configuration made them, to add what
/// no configuration holds (an identification's excitation stage).
using PortsHook = std::function<void(std::vector<runtime::TickPort>& ports)>;

/// How the devices' time passes against the run's ticks. By default a tick runs as soon as the
/// last has computed, and every device's time is the loop's: simulated devices, and drivers whose
/// runtime steps per command (the Force Dimension and Haply stand-ins).
struct DeviceTime {
  /// Steps the clock of a device that keeps its own (a vendor runtime whose servo thread a
  /// stand-in runs on a manual clock): called once before each tick's reading, so that one servo
  /// tick passes per loop tick, as on the bench where both run at the loop's rate.
  std::function<void()> step_device;
  /// Paces the ticks at the loop's rate on CLOCK_MONOTONIC (absolute deadlines, sleep then spin,
  /// as hapticd's loop does, without its real-time priority): for a device that lives in real
  /// time, hardware behind a driver. A tick that starts more than half a period after its
  /// deadline is counted (RunSummary::late_ticks), never skipped: the run's ticks stay whole.
  bool real_time = false;
};

/// Runs `config` (validated; its time mode is ignored: the run is always lockstep) for
/// llround(duration_s · loop rate) ticks and reports every tick of every port to `on_tick`.
/// Energy: trapezoidal on P = F_T_W · v_WT between ticks; positive work adds to the energy given
/// to the device, negative to the energy taken from it.
/// Throws std::invalid_argument naming what is wrong before any work starts; a run that goes
/// unstable returns normally (summary.finite false, fault_ticks counted).
RunSummary simulate_scene(const v1::ServerConfig& config, double duration_s, const TickCallback& on_tick,
                          const PortsHook& adjust_ports = {}, const DeviceTime& device_time = {});

/// simulate_scene with one CSV row per tick and port written to `trace`:
///   port, tick, time_s (s), x_m y_m z_m (p_WT, m), vx_m_s vy_m_s vz_m_s (v_WT, m/s),
///   fx_n fy_n fz_n (F_T_W after the safety stage, N), proxy_x_m proxy_y_m proxy_z_m (p_WP, m),
///   contacts, flags, energy_to_device_j energy_from_device_j (J, so far),
///   q0 q1 q2 (the device's joints, rad or m: JointState) and q0_dot q1_dot q2_dot (rad/s or
///   m/s); the joint cells past the device's joint count are empty; qw qx qy qz (R_WT, identity
///   where the device measures no orientation) and tau_x_nm tau_y_nm tau_z_nm (the torque on the
///   tool after its guard, N·m; 0 but on a device that takes torques). Numbers are written with
///   max_digits10 significant digits (they read back to the same double).
/// Throws std::invalid_argument naming what is wrong before any work starts (nothing written).
RunSummary run_scene(const v1::ServerConfig& config, double duration_s, std::ostream& trace,
                     const std::function<void(std::uint64_t tick, std::uint64_t ticks)>& progress = {});

}  // namespace haptic::lab
