#include "runtime/encoder_device.hpp"

namespace haptic::runtime {

EncoderDevice::EncoderDevice(std::unique_ptr<Device> inner, const EncoderOptions& options)
    : inner_(std::move(inner)), description_(inner_->description()), options_(options), encoder_(options.encoder) {
  for (std::size_t i = 0; i < description_.joints && i < kMaxJoints; ++i) {
    if (options.encoder.quantization[i] > 0.0) description_.capabilities.quantized_position = true;
  }
}

DeviceStatus EncoderDevice::read(DeviceReading& reading) {
  const DeviceStatus status = inner_->read(reading);
  if (status != DeviceStatus::kOk) return status;
  // With tachometers the device's own rates stay; the difference goes nowhere.
  JointVector differenced;
  encoder_.read(reading.q, options_.tachometers ? differenced : reading.q_dot, description_.joints, options_.period_s);
  return status;
}

}  // namespace haptic::runtime
