#pragma once
// Document 003's five-bar (Madill 1998; engine/device/five_bar) as a hapticd device, held at its
// tip by the simulated operator.
//
// Frames: W is the five-bar's base frame x0–y0–z0 (z vertical, origin at the fulcrum); the tool
// point T is the rigid tip of link 5, p_WT = five_bar_tip_position(q). The reading is what the
// hardware would see: joint angles from the encoders (Table 5.2 with the axial −π/6000, counted
// from the home pose; switchable), the tip position from them, and v_WT = J(q_m) q̇_est with q̇_est
// the conventional backward difference of the measured angles through a first-order low-pass
// (L2877–2881, eq. 6.2), or whatever a FiveBarVelocityEstimator supplies instead.
// The command F_T_W becomes τ = Jᵀ(q_m) F (eq. 3.58), saturated per joint at the D/A limit
// (L3237) by the plant. No gravity compensation: the device is balanced (L2371–2380). The
// operator's force acts at the tip through Jᵀ, and a gripping hand's mass moves with the tip.
//
// With options.plant.flexible_mode link 5 carries one horizontal bending mode (engine
// FiveBarFlexibleMode) and capabilities.flexible_modes is set. The hand then holds the physical,
// deflected tip p_rigid(q) + φ1(l) η n(q0), but the reading stays what the sensors give: the
// encoders measure only the joints, so p_WT and v_WT are the rigid tip of the measured joints and
// do not see the deflection (the thesis' strain gauge at the clamp, eq. 3.115, would; it is not
// simulated). plant().physical_tip_state() gives the deflected tip.

#include <cstdint>
#include <memory>

#include "engine/device/five_bar.hpp"
#include "engine/operator/simulated_hand.hpp"
#include "runtime/device.hpp"
#include "runtime/simulated_operator.hpp"

namespace haptic::runtime {

/// A replacement for the backward-difference velocity (e.g. Madill's non-linear state
/// estimator, ch. 6.3). Called on the loop: must not allocate, lock or throw.
class FiveBarVelocityEstimator {
 public:
  virtual ~FiveBarVelocityEstimator() = default;
  /// Off the loop, and when installed: the device is at rest at q_measured (rad).
  virtual void reset(const engine::FiveBarJoints& q_measured) = 0;
  /// Once per tick, after the plant advanced by dt (s): the measured angles (rad), the saturated
  /// joint torque applied over the tick (N·m, what L3230 says to feed back), and the operator's
  /// joint torque Jᵀ F_hand at the sample (N·m; what the strain gauges measure). Returns the
  /// joint velocity estimate (rad/s).
  virtual engine::FiveBarJoints update(const engine::FiveBarJoints& q_measured,
                                       const engine::FiveBarJoints& tau_applied,
                                       const engine::FiveBarJoints& tau_user, double dt) = 0;
};

struct SimulatedFiveBarOptions {
  engine::FiveBarPlantOptions plant;  // RK4 × 10 sub-steps, Coriolis on, rigid link 5.
  bool quantized = true;              // Read the angles through the encoders.
  double velocity_cutoff = 20.0;      // ω0 of the velocity low-pass (L3193). Unit: rad/s.
  /// Largest tool force the server may command: ≈ the smallest joint limit over the 0.6 m arm
  /// (7.22 N·m / 0.6 m). Unit: N.
  double max_force = 12.0;
};

class SimulatedFiveBarDevice final : public Device {
 public:
  SimulatedFiveBarDevice(const engine::FiveBarParams& params,
                         const engine::FiveBarState& initial = {},
                         const SimulatedFiveBarOptions& options = {});

  const DeviceDescription& description() const override { return description_; }
  DeviceStatus start() override { return DeviceStatus::kOk; }
  void stop() override {}
  DeviceStatus read(DeviceReading& reading) override;
  DeviceStatus write(const DeviceCommand& command, double dt) override;

  /// Off the loop: what the simulated hand does from the next tick on.
  void set_hand(const engine::HandInput& input) { hand_.set(input); }

  /// Off the loop, before start(): a velocity estimator to use instead of the backward
  /// difference (nullptr restores it). Sets capabilities.state_estimator accordingly.
  void set_velocity_estimator(std::unique_ptr<FiveBarVelocityEstimator> estimator);

  const engine::FiveBarPlant& plant() const { return plant_; }
  /// Off the loop (tests, resets): replaces the plant state, puts the flexible mode at rest and
  /// restarts the sensing at rest.
  void set_plant_state(const engine::FiveBarState& state);
  /// The joint angles as last measured. Unit: rad.
  const engine::FiveBarJoints& measured_joints() const { return q_measured_; }

 private:
  engine::FiveBarJoints measure(const engine::FiveBarJoints& q) const;

  DeviceDescription description_;
  SimulatedFiveBarOptions options_;
  engine::FiveBarPlant plant_;
  SimulatedOperator hand_;
  engine::BackwardDifferenceVelocity difference_;
  std::unique_ptr<FiveBarVelocityEstimator> estimator_;
  engine::FiveBarJoints q_measured_{};     // Unit: rad.
  engine::FiveBarJoints qdot_estimate_{};  // Unit: rad/s.
};

}  // namespace haptic::runtime
