#pragma once
// What the loop knows about a kind of device, beside the device itself (runtime/device.hpp): its
// kinematics and Jacobian, gravity compensation, the brake/motor power rule, a watchdog, a state
// estimator, a disturbance observer. The same model serves the simulated plant and the real
// hardware of that kind; the TickRunner runs it as stages of every tick at the device's port:
//   device.read → estimate → kinematics → (scene, passivity, force guard) → joint_command → device.write
// Every stage runs on the loop: no allocation, lock or throw.

#include "runtime/device.hpp"

namespace haptic::runtime {

/// The joints' state the estimate stage gives: what kinematics and joint_command work from.
struct JointState {
  JointVector q{};      // Unit per joint: rad or m.
  JointVector q_dot{};  // Unit per joint: rad/s or m/s.
};

class DeviceModel {
 public:
  virtual ~DeviceModel() = default;

  /// Stage "estimate": the joint state from a reading taken `dt` seconds after the previous one.
  /// `first`: there is no previous one (the loop's first tick): estimators start at rest here.
  virtual void estimate(const DeviceReading& reading, double dt, bool first, JointState& joints) = 0;

  /// Stage "kinematics": the tool point's state at `joints` (the model keeps what joint_command
  /// needs of it, e.g. the Jacobian).
  virtual void kinematics(const JointState& joints, ToolReading& tool) = 0;

  /// True while the model holds the device in its safe state (a tripped watchdog); the loop then
  /// commands zero force and joint_command gives the safe command.
  virtual bool holds_safe_state() const { return false; }

  /// Stage "Jᵀ": the joint command that puts `command` on the tool point over the next `dt`
  /// seconds (τ = Jᵀ F and whatever the device needs beside it: gravity compensation, an
  /// observer's correction, the brake split, joint limits). `reading` and `joints` are this tick's.
  /// kError for a command the model cannot apply (non-finite, a period it was not designed for):
  /// `out` is then the safe command.
  virtual DeviceStatus joint_command(const ToolCommand& command, const DeviceReading& reading,
                                     const JointState& joints, double dt, DeviceCommand& out) = 0;

  /// The command that holds the device safe: motors at zero, brakes at their limits.
  virtual void safe_command(DeviceCommand& out) const { out = {}; }

  /// On a device fault: a model that latches its safe state (a watchdog) enters it.
  virtual void enter_safe_state() {}
};

}  // namespace haptic::runtime
