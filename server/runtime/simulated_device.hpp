#pragma once
// What a simulated device has beyond the device seam: the simulated operator who holds it, and the
// plant's true joint state (which no sensor gives, for haptic-lab's records and tests).

#include <array>
#include <cstdint>
#include <optional>

#include "engine/operator/simulated_hand.hpp"
#include "runtime/device.hpp"
#include "runtime/simulated_operator.hpp"

namespace haptic::runtime {

/// A 3-joint plant at its present state as the tool point sees it: joint-space inertia and viscous
/// damping, and the Jacobian from those joints to the tool point (v_WT = J q̇). Units: kg·m² or
/// kg; N·m·s/rad or N·s/m; m/rad or 1, per joint.
struct JointSpaceDynamics {
  using Matrix = std::array<std::array<double, 3>, 3>;
  Matrix inertia{};
  Matrix damping{};
  Matrix jacobian{};
};

class SimulatedDevice : public Device {
 public:
  const DeviceDescription& description() const final { return description_; }
  /// A simulated plant needs no bringing up or down unless its device says otherwise.
  DeviceStatus start() override { return DeviceStatus::kOk; }
  void stop() override {}

  /// Off the loop: what the simulated hand does from the next tick on.
  void set_hand(const engine::HandInput& input) { hand_.set(input); }

  /// The plant's true joint coordinates and rates (not the sensors'), in the order and units of
  /// the device's documentation; returns how many (0: the device reports none).
  virtual std::uint32_t plant_joints(JointVector& q, JointVector& q_dot) const = 0;

  /// For a device whose apparent mass depends on the pose (no DeviceDescription::apparent_mass):
  /// its joint-space dynamics now; nullopt for the others.
  virtual std::optional<JointSpaceDynamics> joint_space_dynamics() const { return std::nullopt; }

 protected:
  DeviceDescription description_;  // filled in by the device's constructor
  SimulatedOperator hand_;          // the simulated operator holding the tool
};

}  // namespace haptic::runtime
