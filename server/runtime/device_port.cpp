#include "runtime/device_port.hpp"

#include <algorithm>
#include <cmath>

namespace haptic::runtime {

namespace {

bool finite(const JointVector& values, std::size_t count) {
  for (std::size_t i = 0; i < count; ++i) {
    if (!std::isfinite(values[i])) return false;
  }
  return true;
}

}  // namespace

DevicePort::DevicePort(Device& device, DeviceModel& model)
    : device_(&device),
      model_(&model),
      joints_count_(std::min<std::size_t>(device.description().joints, kMaxJoints)) {}

DeviceStatus DevicePort::read_device() {
  if (device_->read(reading_) != DeviceStatus::kOk) return DeviceStatus::kError;
  const std::size_t n = joints_count_;
  const engine::Quat& R = reading_.R_WT;
  return finite(reading_.q, n) && finite(reading_.q_dot, n) && finite(reading_.tau_sensor, n) &&
                 engine::is_finite(reading_.F_sensor_W) && engine::is_finite(reading_.w_WT) &&
                 std::isfinite(R.w) &&
                 std::isfinite(R.x) && std::isfinite(R.y) && std::isfinite(R.z)
             ? DeviceStatus::kOk
             : DeviceStatus::kError;
}

void DevicePort::estimate() {
  model_->estimate(reading_, elapsed_s_, first_, joints_);
  first_ = false;
  elapsed_s_ = 0.0;
}

bool DevicePort::kinematics() {
  // What the sensors give directly; a model that computes the orientation from joints overwrites it.
  tool_.R_WT = reading_.R_WT;
  tool_.w_WT = reading_.w_WT;
  model_->kinematics(joints_, tool_);
  tool_.buttons = reading_.buttons;
  tool_.safe_state = reading_.safe_state || model_->holds_safe_state();
  return engine::is_finite(tool_.p_WT) && engine::is_finite(tool_.v_WT);
}

void DevicePort::enter_safe_state() {
  model_->enter_safe_state();
  device_->enter_safe_state();
  model_->safe_command(command_);
  command_.tau_W = {};
}

DeviceStatus DevicePort::write_device(double dt) {
  elapsed_s_ += dt;
  read_since_write_ = false;
  return device_->write(command_, dt);
}

DeviceStatus DevicePort::read(ToolReading& tool) {
  if (!read_since_write_) {
    // As the loop does: a failed reading is not estimated from, and puts the device safe.
    const bool ok = sense();
    last_read_ = ok ? DeviceStatus::kOk : DeviceStatus::kError;
    if (!ok) enter_safe_state();
    read_since_write_ = true;
  }
  tool = tool_;
  return last_read_;
}

DeviceStatus DevicePort::write(const ToolCommand& command, double dt) {
  if (!read_since_write_) {
    ToolReading unused;
    read(unused);
  }
  DeviceStatus model_status = DeviceStatus::kError;  // the safe command is in place after a bad read
  if (last_read_ == DeviceStatus::kOk) model_status = joint_command(command, dt);
  const DeviceStatus device_status = write_device(dt);
  return model_status == DeviceStatus::kOk && device_status == DeviceStatus::kOk ? DeviceStatus::kOk
                                                                                 : DeviceStatus::kError;
}

}  // namespace haptic::runtime
