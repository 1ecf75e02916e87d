#pragma once
// The device seam: what the loop talks to, simulated plant or real hardware behind the same
// interface (after ros2_control's hardware interface: a lifecycle, then real-time read/write that
// return a status and never throw).

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

#include "engine/core/vec3.hpp"

namespace haptic::runtime {

enum class DeviceStatus : std::uint8_t { kOk, kError };

/// Most joints a device reads and commands (actuated, braked or only measured).
inline constexpr std::size_t kMaxJoints = 6;

/// One value per joint, in the device's joint order; entries past DeviceDescription::joints are 0.
/// Units per joint: rad (revolute) or m (prismatic), and their rates and efforts (N·m or N).
using JointVector = std::array<double, kMaxJoints>;

/// What the device's sensors give once per tick, at the joints: encoders, tachometers, torque or
/// force sensors, buttons. Nothing here is computed from a model; the DeviceModel turns it into
/// the tool point's state.
struct DeviceReading {
  JointVector q{};      // Joint positions as measured (encoder counts applied).
  /// Joint rates where the device measures them (tachometers; capabilities.measured_rates), else 0
  /// and the model estimates them from q.
  JointVector q_dot{};
  /// The operator's effort at each joint as joint-torque sensors (strain gauges) measure it; 0
  /// without them.
  JointVector tau_sensor{};
  /// The operator's force on the handle as a handle load cell measures it, in W. Unit: N. 0
  /// without one (capabilities.force_sensor).
  engine::Vec3 F_sensor_W;
  /// The tool's orientation in W as the device's gimbal measures it (capabilities.orientation),
  /// a unit quaternion; identity without one.
  engine::Quat R_WT;
  /// The tool's angular velocity in W where the device measures orientation (capabilities.
  /// orientation), else 0. Unit: rad/s.
  engine::Vec3 w_WT;
  /// Pressed buttons, bit i for button i (DeviceDescription::buttons of them).
  std::uint32_t buttons = 0;
  /// The device holds its own safe state (a hardware watchdog or an emergency stop: motors off,
  /// brakes on) although the reading is good: the loop treats the tick as a device fault (zero
  /// force, DEVICE_FAULT flag and event) but still publishes where the device is.
  bool safe_state = false;
};

/// What the loop commands once per tick, at the joints: held over the tick (zero-order hold).
struct DeviceCommand {
  JointVector tau{};    // Actuator effort per joint: N·m or N.
  /// Brake effort limit per joint, >= 0 (devices with brakes; capabilities.brakes): N·m or N.
  JointVector brake{};
  /// Torque on the handle about the tool point, in W (devices that take torques; capabilities.
  /// torque), else 0. Unit: N·m.
  engine::Vec3 tau_W;
};

/// The tool point's state the model computes from a reading. Frames: W (device world), T (tool).
struct ToolReading {
  engine::Vec3 p_WT;  // Unit: m.
  engine::Vec3 v_WT;  // Unit: m/s.
  engine::Quat R_WT;  // The tool's orientation (capabilities.orientation), else identity.
  engine::Vec3 w_WT;  // Its angular velocity in W, else 0. Unit: rad/s.
  /// A device or model safe state (see DeviceReading::safe_state and DeviceModel).
  bool safe_state = false;
  std::uint32_t buttons = 0;
};

/// The force (and, for a device that takes torques, the torque) the scene asks of the tool.
struct ToolCommand {
  engine::Vec3 F_T_W{};    // Force on the tool, in W. Unit: N.
  engine::Vec3 tau_T_W{};  // Torque on the tool, in W (capabilities.torque). Unit: N·m.
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
  bool measured_rates = false;  // Joint rates come from tachometers (DeviceReading::q_dot).
  bool orientation = false;     // The tool's orientation is measured (DeviceReading::R_WT, w_WT).
  bool torque = false;          // The handle takes torques (DeviceCommand::tau_W); needs orientation.
};

struct DeviceDescription {
  std::string name;
  /// Configuration name of the model ("point_mass", "dc_motor_000", "five_bar_003", …).
  std::string model;
  DeviceCapabilities capabilities;
  std::uint32_t dof = 3;     // Degrees of freedom of the tool point.
  std::uint32_t joints = 3;  // Entries of the JointVectors read and written, <= kMaxJoints.
  std::uint32_t buttons = 0; // Buttons reported in DeviceReading::buttons.
  engine::Vec3 workspace_min;  // Unit: m.
  engine::Vec3 workspace_max;  // Unit: m.
  double max_force = 0.0;      // Unit: N.
  bool simulated = false;
  /// The device at its tool point as a mass-damper per axis (for the stability report of a wall);
  /// 0 when the device gives no such model. Units: kg, N·s/m.
  double apparent_mass = 0.0;
  double apparent_damping = 0.0;
  /// The delay between a command and its effect beyond a perfect loop's half tick, where it is
  /// known (a driver port's measured profile, docs/identification.md); the stability report counts
  /// it. Unit: s. 0: none known.
  double delay_s = 0.0;
  /// The force's first-order lag behind the command, where known (the same profile): the
  /// stability report samples it exactly. Unit: s. 0: none known.
  double actuator_lag_s = 0.0;
  /// The same for the handle's rotation (an inertia-damper per axis; capabilities.torque), for
  /// the stability report of an orientation spring; 0 when unknown. Units: kg·m², N·m·s/rad.
  double apparent_inertia = 0.0;
  double apparent_rotational_damping = 0.0;
  double max_torque = 0.0;     // capabilities.torque. Unit: N·m.
};

/// A device at its joints: a plant and its sensors and actuators, simulated or real. Everything
/// that needs a model of the device (kinematics, Jᵀ, gravity compensation, brake rule, watchdog,
/// estimators) is its DeviceModel's, run by the loop as stages of the tick.
class Device {
 public:
  virtual ~Device() = default;

  /// Off the loop: identity and limits.
  virtual const DeviceDescription& description() const = 0;

  /// Off the loop, before the first tick / after the last.
  virtual DeviceStatus start() = 0;
  virtual void stop() = 0;

  /// On the loop: the sensors now. Must not allocate, lock or throw.
  virtual DeviceStatus read(DeviceReading& reading) = 0;
  /// On the loop: `command` held for the tick of `dt` seconds. A simulated device advances its
  /// plant by dt here, so the next read() sees the state one period later. A non-finite effort is
  /// an error: the device applies none that tick.
  virtual DeviceStatus write(const DeviceCommand& command, double dt) = 0;

  /// On the loop, when a read or write has failed: motors to zero, brakes on where the device
  /// has them. Must not throw.
  virtual void enter_safe_state() {}

  /// Off the loop, while it runs: why the most recent read or write failed, in the device's own
  /// words ("" when it cannot say), for the DEVICE_FAULT event and the log.
  virtual std::string fault_reason() const { return {}; }
};

}  // namespace haptic::runtime
