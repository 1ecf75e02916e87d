#pragma once
// A simulated device with its model, driven at its tool point through a DevicePort exactly as the
// loop's stages drive it (read → estimate → kinematics; Jᵀ → write). The device's own accessors
// are reached with ->, the model's through .model.

#include <utility>

#include "runtime/device_port.hpp"

namespace haptic::runtime {

template <typename SimDevice, typename Model>
struct Modelled {
  template <typename... DeviceArgs>
  explicit Modelled(Model model_in, DeviceArgs&&... args)
      : device(std::forward<DeviceArgs>(args)...), model(std::move(model_in)) {}
  Modelled(const Modelled&) = delete;
  Modelled& operator=(const Modelled&) = delete;

  SimDevice* operator->() { return &device; }
  const SimDevice* operator->() const { return &device; }
  DeviceStatus read(ToolReading& reading) { return port.read(reading); }
  DeviceStatus write(const ToolCommand& command, double dt) { return port.write(command, dt); }

  SimDevice device;
  Model model;
  DevicePort port{device, model};
};

}  // namespace haptic::runtime
