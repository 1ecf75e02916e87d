#pragma once
// A ROS 2 node's wrench at one device port, a stage of the tick (docs/architecture.md, steps 6
// and 8): the newest wrench from the mailbox (robot_wrench.hpp), scaled and refused when not
// finite, its gain ramped in while wrenches come and out once they stop, its force through a
// network passivity layer of its own (engine::from_passive_source: first scaled down to what the
// layer's reservoir pays for), and its torque the same way on a port that takes torques and knows
// its inertia. Only with federation.ros2.wrench_input: elsewhere a port has no stage.

#include <atomic>
#include <cstdint>
#include <optional>

#include "engine/core/rotation.hpp"
#include "engine/core/vec3.hpp"
#include "engine/safety/network_passivity.hpp"
#include "runtime/device.hpp"
#include "runtime/latest_value.hpp"
#include "runtime/robot_wrench.hpp"

namespace haptic::runtime {

class RobotWrenchStage {
 public:
  /// mailbox: what the federation writes (not owned); what is in it already is not rendered again
  /// (stale until a new wrench comes). torque: the port renders torques (its torque guard), so the
  /// wrench's torque goes to it where the device knows its apparent inertia. refused: the loop's
  /// counter of non-finite wrenches. period_s: the tick (s); ramp_ticks: the ramp's length (≥ 1).
  RobotWrenchStage(const LatestValue<RobotWrench>& mailbox, const RobotWrenchParams& params,
                   const DeviceDescription& description, bool torque, double period_s, std::int64_t ramp_ticks,
                   std::atomic<std::uint64_t>& refused);

  /// On the loop, once a tick with a good reading, before torque(): takes a new wrench and ages the
  /// last; the force on the tool through its layer. Unit: N, in W.
  engine::Vec3 force(const ToolReading& reading);
  /// Whether the port renders the wrench's torque.
  bool has_torque() const { return torque_layer_.has_value(); }
  /// After force(), where has_torque(): the torque on the handle through its layer. Unit: N·m, in W.
  engine::Vec3 torque(const ToolReading& reading);

 private:
  const LatestValue<RobotWrench>& mailbox_;
  RobotWrenchParams params_;
  double apparent_mass_;     // kg; 0: unknown
  double apparent_inertia_;  // kg·m²
  double period_s_;
  std::int64_t ramp_ticks_;
  std::atomic<std::uint64_t>& refused_;
  engine::NetworkPassivity layer_;
  std::uint64_t sequence_ = 0;  // the newest wrench seen
  engine::Vec3 F_T_W_{};        // the newest finite one's force, scaled. Unit: N.
  std::int64_t age_ticks_ = 0;  // ticks since it came (counted until it is stale)
  double gain_ = 0.0;           // its ramp: 0 ... 1
  /// Its torque: the layer, the newest finite torque (scaled; N·m), and the handle's rotation
  /// summed since the port was made (rad).
  std::optional<engine::NetworkPassivity> torque_layer_;
  engine::Vec3 tau_T_W_{};
  engine::Vec3 theta_W_{};
  engine::Quat R_previous_{};
  bool R_known_ = false;
};

}  // namespace haptic::runtime
