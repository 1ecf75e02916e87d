#pragma once
// Document 003's five-bar (Madill 1998; engine/device/five_bar) as the loop models it.
//
// Frames: W is the five-bar's base frame x0–y0–z0 (z vertical, origin at the fulcrum); the tool
// point T is the rigid tip of link 5, p_WT = five_bar_tip_position(q). The joints are the three
// motor angles as the encoders give them (rad); their rates are estimated: the conventional
// backward difference through a first-order low-pass (L2877–2881, eq. 6.2), or whatever a
// FiveBarVelocityEstimator supplies instead, and v_WT = J(q_m) q̇_est. The command F_T_W becomes
// τ = Jᵀ(q_m) F (eq. 3.58), saturated per joint at the D/A limit (L3237). No gravity
// compensation: the device is balanced (L2371–2380).

#include <memory>

#include "engine/device/five_bar.hpp"
#include "runtime/device_model.hpp"

namespace haptic::runtime {

/// A replacement for the backward-difference velocity (e.g. Madill's non-linear state
/// estimator, ch. 6.3). Called on the loop: must not allocate, lock or throw.
class FiveBarVelocityEstimator {
 public:
  virtual ~FiveBarVelocityEstimator() = default;
  /// The device is at rest at q_measured (rad).
  virtual void reset(const engine::FiveBarJoints& q_measured) = 0;
  /// Once per tick, `dt` (s) after the previous: the measured angles (rad), the saturated joint
  /// torque applied over the last tick (N·m, what L3230 says to feed back), and the operator's
  /// joint torque at the sample (N·m; what the strain gauges measure). Returns the joint velocity
  /// estimate (rad/s).
  virtual engine::FiveBarJoints update(const engine::FiveBarJoints& q_measured,
                                       const engine::FiveBarJoints& tau_applied,
                                       const engine::FiveBarJoints& tau_user, double dt) = 0;
};

class FiveBarModel final : public DeviceModel {
 public:
  /// `velocity_cutoff`: ω0 of the backward difference's low-pass (L3193). Unit: rad/s.
  FiveBarModel(const engine::FiveBarParams& params, double velocity_cutoff);

  /// Off the loop: a velocity estimator to use instead of the backward difference (nullptr
  /// restores it); it starts at the next estimate as at the first.
  void set_velocity_estimator(std::unique_ptr<FiveBarVelocityEstimator> estimator);
  bool has_velocity_estimator() const { return estimator_ != nullptr; }

  void estimate(const DeviceReading& reading, double dt, bool first, JointState& joints) override;
  void kinematics(const JointState& joints, ToolReading& tool) override;
  /// kError for a non-finite force (the zero command is given).
  DeviceStatus joint_command(const ToolCommand& command, const DeviceReading& reading,
                             const JointState& joints, double dt, DeviceCommand& out) override;

 private:
  engine::FiveBarParams params_;
  engine::BackwardDifferenceVelocity difference_;
  std::unique_ptr<FiveBarVelocityEstimator> estimator_;
  engine::FiveBarJoints applied_{};  // the saturated torque commanded for the last tick. Unit: N·m.
  bool restart_ = false;             // the estimator changed: start it at rest
};

}  // namespace haptic::runtime
