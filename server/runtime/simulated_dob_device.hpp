#pragma once
// Document 001's device as a hapticd device: the 2-DOF parallel (five-bar) mechanism of
// engine/device/parallel_2dof with a disturbance observer on each Cartesian axis
// (engine/control/disturbance_observer; Eom, Suh, Yi, eqs. 2–5, Fig. 1), held by the simulated
// operator at its end effector.
//
// The tool point T is the end effector in the device plane: p_WT = (x, y, 0), v_WT = (ẋ, ẏ, 0);
// the plane is horizontal, so there is no gravity load. Per tick k (the loop's period T must be the
// observer's sample_period):
//   1. the handle's force sensor reads the operator's force F_h,k (simulated: the hand's force at
//      the tick's start state; the observer needs it, otherwise it would reject the operator's
//      push as a disturbance — an inference: the document's −5 N "force command of the human
//      operator" was known to its controller);
//   2. each axis's observer turns the scene's force F_T_W into u_i = F_i + F̂_d,i;
//   3. the motors get τ = Jᵀ u, saturated at max_joint_torque and held over the tick;
//   4. the plant advances by T with the operator's force on the end effector (re-evaluated at every
//      integration stage); each observer is updated with the force actually applied,
//      (J^{-T} τ_sat)_i + F_h,i.
// Below the observer's cut-off the tool therefore moves as M̄ ẍ + B̄ ẋ = F + F_h on each axis
// (eq. 5), whatever the pose. The z component of the scene's force has nothing to act on.
// A hand that follows a target adds its mass to the end effector (the observer, seeing it as a
// disturbance, hides it below the cut-off: a limitation of the simulated sensor, which measures
// only the hand's spring-damper force).

#include <array>
#include <cstdint>

#include "engine/control/disturbance_observer.hpp"
#include "engine/device/parallel_2dof.hpp"
#include "engine/operator/simulated_hand.hpp"
#include "runtime/device.hpp"
#include "runtime/simulated_operator.hpp"

namespace haptic::runtime {

class SimulatedDobDevice final : public Device {
 public:
  /// `plant`, `observer`: validated parameters (validate() returns ""); observer.sample_period is
  /// the loop period. `initial_p_WT`: the end effector's start, reachable (z ignored). Unit: m.
  /// `max_force`: reported to the loop's force guard. Unit: N. `observer_enabled` false gives the
  /// bare coupled device (the scene's force straight to τ = Jᵀ F), for comparison.
  SimulatedDobDevice(const engine::Parallel2DofParams& plant,
                     const engine::DisturbanceObserverParams& observer,
                     const engine::Vec3& initial_p_WT, double max_force,
                     bool observer_enabled = true);

  const DeviceDescription& description() const override { return description_; }
  DeviceStatus start() override { return DeviceStatus::kOk; }
  void stop() override {}
  /// kError when the state is not finite (a NaN, or the end effector out of reach).
  DeviceStatus read(DeviceReading& reading) override;
  /// kError, without advancing, for a non-finite force or a dt other than the observer's period;
  /// kError after advancing when the state has become non-finite.
  DeviceStatus write(const DeviceCommand& command, double dt) override;

  /// Off the loop: what the simulated hand does from the next tick on.
  void set_hand(const engine::HandInput& input) { hand_.set(input); }

  const engine::Parallel2DofPlant& plant() const { return plant_; }
  /// The observers' last estimates F̂_d (x, y), N; zero when disabled.
  engine::Vec3 disturbance_estimate() const;
  /// The operator's force the handle sensor read on the last tick, in W. Unit: N.
  const engine::Vec3& measured_hand_force() const { return hand_force_; }

 private:
  DeviceDescription description_;
  engine::Parallel2DofPlant plant_;
  std::array<engine::DisturbanceObserver, 2> observers_;
  bool observer_enabled_;
  double period_;  // Unit: s.
  engine::Vec3 hand_force_;
  SimulatedOperator hand_;
};

}  // namespace haptic::runtime
