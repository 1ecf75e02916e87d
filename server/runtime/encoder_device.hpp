#pragma once
// A simulated device read through encoders (docs/identification.md): the port sees each joint's
// angle with noise and then quantization to a step, as a real device's encoders report it, and
// the rates either the backward difference of those angles (a device that counts an encoder) or
// the device's own rate sensors (004's tachometers). Only what the port reads changes: a loop
// inside the device (001's disturbance observer) still sees its plant's true state.

#include <cstddef>
#include <memory>
#include <string>

#include "engine/device/position_sensor.hpp"
#include "runtime/device.hpp"

namespace haptic::runtime {

struct EncoderOptions {
  engine::JointEncoderParams<kMaxJoints> encoder;
  /// Keep the device's own rates (its tachometers) instead of differencing the measured angles.
  bool tachometers = false;
  double period_s = 1e-3;  // the loop's, for the difference. Unit: s.
};

class EncoderDevice final : public Device {
 public:
  /// `inner` read through encoders; every other call passes through unchanged.
  /// The description is the inner device's (a simulated one's is fixed), saying its position is
  /// quantized where a step is set.
  EncoderDevice(std::unique_ptr<Device> inner, const EncoderOptions& options);

  const DeviceDescription& description() const override { return description_; }
  DeviceStatus start() override { return inner_->start(); }
  void stop() override { inner_->stop(); }
  DeviceStatus read(DeviceReading& reading) override;
  DeviceStatus write(const DeviceCommand& command, double dt) override { return inner_->write(command, dt); }
  void enter_safe_state() override { inner_->enter_safe_state(); }
  std::string fault_reason() const override { return inner_->fault_reason(); }

 private:
  std::unique_ptr<Device> inner_;
  DeviceDescription description_;
  EncoderOptions options_;
  engine::JointEncoder<kMaxJoints> encoder_;
};

}  // namespace haptic::runtime
