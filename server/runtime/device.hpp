#pragma once
// The device seam: what the loop talks to, simulated plant or real hardware behind the same
// interface (after ros2_control's hardware interface: a lifecycle, then real-time read/write that
// return a status and never throw).

#include <cstdint>
#include <string>

#include "engine/core/vec3.hpp"

namespace haptic::runtime {

enum class DeviceStatus : std::uint8_t { kOk, kError };

/// What a device reports once per tick. Frames: W (device world), T (tool point).
struct DeviceReading {
  engine::Vec3 p_WT;  // Unit: m.
  engine::Vec3 v_WT;  // Unit: m/s.
  /// The device holds its safe state (a tripped watchdog: motors off, brakes on) although the
  /// reading is good: the loop treats the tick as a device fault (zero force, DEVICE_FAULT flag
  /// and event) but still publishes this reading.
  bool safe_state = false;
};

/// What the loop commands once per tick.
struct DeviceCommand {
  engine::Vec3 F_T_W;  // Force on the tool, in W. Unit: N.
};

/// What a device has, so the tick and the device compute only those terms (a balanced device gets
/// no gravity compensation, a device without brakes no motor/brake split). Declared once, off the
/// loop; the server reports it in DeviceInfo.
struct DeviceCapabilities {
  bool gravity = false;         // The plant carries a gravity load the device compensates.
  bool brakes = false;          // Dissipative actuators beside the motors (power-based split).
  bool flexible_modes = false;  // Structural modes are simulated.
  bool friction = false;        // Joint or transmission friction is simulated.
  bool force_sensor = false;    // A measured interaction force is available.
  bool quantized_position = false;  // Positions come from encoder counts.
  bool state_estimator = false; // Velocities come from an observer rather than differences.
  bool disturbance_observer = false;  // Axes are shaped to a nominal model by a DOB.
};

struct DeviceDescription {
  std::string name;
  /// Configuration name of the model ("point_mass", "dc_motor_000", "five_bar_003", …).
  std::string model;
  DeviceCapabilities capabilities;
  std::uint32_t dof = 3;
  engine::Vec3 workspace_min;  // Unit: m.
  engine::Vec3 workspace_max;  // Unit: m.
  double max_force = 0.0;      // Unit: N.
  bool simulated = false;
  /// The device at its tool point as a mass-damper per axis (for the stability report of a wall);
  /// 0 when the device gives no such model. Units: kg, N·s/m.
  double apparent_mass = 0.0;
  double apparent_damping = 0.0;
};

class Device {
 public:
  virtual ~Device() = default;

  /// Off the loop: identity and limits.
  virtual const DeviceDescription& description() const = 0;

  /// Off the loop, before the first tick / after the last.
  virtual DeviceStatus start() = 0;
  virtual void stop() = 0;

  /// On the loop. `dt` is the tick period (s): a simulated device advances its plant by dt in
  /// write(), so the next read() sees the state one period later (a zero-order hold of the command).
  virtual DeviceStatus read(DeviceReading& reading) = 0;
  virtual DeviceStatus write(const DeviceCommand& command, double dt) = 0;

  /// On the loop, when a read or write has failed: motors to zero torque, brakes on where the
  /// device has them. The loop goes on commanding zero force while the fault lasts; a device that
  /// latches its safe state (a tripped watchdog) leaves it only when re-armed. Must not throw.
  virtual void enter_safe_state() {}
};

}  // namespace haptic::runtime
