#pragma once
// One device with its model at a port of the loop: the stages of one tick, in order,
//   read_device → estimate → kinematics → … → joint_command → write_device
// with what each stage leaves for the next. The TickRunner runs the stages with the scene,
// passivity and force guard between them; haptic-lab, benches and tests drive a port as one device
// at its tool point through read() and write().

#include "runtime/device.hpp"
#include "runtime/device_model.hpp"

namespace haptic::runtime {

class DevicePort {
 public:
  /// Neither is owned; both outlive the port.
  DevicePort(Device& device, DeviceModel& model);

  Device& device() const { return *device_; }
  DeviceModel& model() const { return *model_; }
  const DeviceDescription& description() const { return device_->description(); }

  // ---- The stages, in tick order ----

  /// The device's sensors. kError when the device reports one or a reading is not finite (so no
  /// NaN reaches an estimator).
  DeviceStatus read_device();
  /// The model's joint state from the reading, over the time written since the last estimate.
  void estimate();
  /// The tool point's state from the joint state; false when it is not finite. The tool reading's
  /// safe_state is the device's or the model's.
  bool kinematics();
  /// The joint command for a tool force (the model's Jᵀ stage); kError when the model refuses it
  /// (the safe command is then in command()).
  /// The torque passes through to the handle as it is (no model maps it to joints yet).
  DeviceStatus joint_command(const ToolCommand& command, double dt) {
    command_.tau_W = command.tau_T_W;
    return model_->joint_command(command, reading_, joints_, dt, command_);
  }
  /// read_device, then (when it succeeded) estimate and kinematics: the tool point's state in
  /// tool(). False when the device reports an error or a state is not finite.
  bool sense() { return read_device() == DeviceStatus::kOk && (estimate(), kinematics()); }
  /// A device fault: the model's and the device's safe states; command() becomes the safe one.
  void enter_safe_state();
  /// Writes command() for `dt` seconds.
  DeviceStatus write_device(double dt);

  // ---- The whole device at its tool point ----

  /// read_device, estimate, kinematics. kError when the device reports one or the state is not
  /// finite. A second read() with no write() between gives the first's result again.
  DeviceStatus read(ToolReading& tool);
  /// joint_command and write_device (reading first when nothing was read since the last write).
  /// kError when the model refuses the command (the safe command is written) or the device
  /// reports an error.
  DeviceStatus write(const ToolCommand& command, double dt);
  /// The next estimate starts the estimators at rest (after the device was put somewhere else).
  void restart_estimation() { first_ = true; elapsed_s_ = 0.0; read_since_write_ = false; }

  const DeviceReading& reading() const { return reading_; }
  const JointState& joints() const { return joints_; }
  const ToolReading& tool() const { return tool_; }
  const DeviceCommand& command() const { return command_; }

 private:
  Device* device_;
  DeviceModel* model_;
  std::size_t joints_count_;  // the device's joints, the entries a reading must have finite
  DeviceReading reading_;
  JointState joints_;
  ToolReading tool_;
  DeviceCommand command_;
  double elapsed_s_ = 0.0;  // written since the last estimate. Unit: s.
  bool first_ = true;       // no estimate yet
  bool read_since_write_ = false;
  DeviceStatus last_read_ = DeviceStatus::kOk;
};

}  // namespace haptic::runtime
