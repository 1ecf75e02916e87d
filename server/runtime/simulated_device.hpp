#pragma once
// The default device: the 3-DOF point-mass plant (engine/device) held by a simulated operator
// (engine/operator). The operator's input is changed off the loop (SetOperator RPC) through a
// lock-free mailbox; its profiles and trajectories run on the device's own (simulated) clock from
// the tick the input arrives, so lockstep runs stay exactly reproducible.

#include "engine/device/point_mass_plant.hpp"
#include "engine/operator/simulated_hand.hpp"
#include "runtime/device.hpp"
#include "runtime/simulated_operator.hpp"

#include <cstdint>

namespace haptic::runtime {

class SimulatedPointMassDevice final : public Device {
 public:
  SimulatedPointMassDevice(const engine::PointMassParams& params,
                           const engine::PointMassState& initial, double max_force);

  const DeviceDescription& description() const override { return description_; }
  DeviceStatus start() override { return DeviceStatus::kOk; }
  void stop() override {}
  DeviceStatus read(DeviceReading& reading) override;
  DeviceStatus write(const DeviceCommand& command, double dt) override;

  /// Off the loop: what the simulated hand does from the next tick on.
  void set_hand(const engine::HandInput& input) { hand_.set(input); }

 private:
  DeviceDescription description_;
  engine::PointMassPlant plant_;
  SimulatedOperator hand_;
};

}  // namespace haptic::runtime
