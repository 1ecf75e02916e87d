#pragma once
// A force a ROS 2 node asks for on a device port's tool (docs/federation.md, "A robot's wrench on
// the tool"): a robot's measured wrench, say, that its user should feel. The federation's thread
// writes each accepted geometry_msgs/msg/WrenchStamped into the port's mailbox; the loop renders
// the force through a network passivity layer of its own (the robot is a remote site that books
// no energy: the layer's reservoir holds only what this port's user put in against the force),
// the torque through another where the port takes torques, and ramps both out when no new wrench
// has come for stale_s.

#include <cstdint>

#include "engine/core/vec3.hpp"

namespace haptic::runtime {

/// The newest wrench accepted from the node. The relay checks it (frame, finite) before storing;
/// the loop checks that it is finite again and refuses it otherwise.
struct RobotWrench {
  std::uint64_t sequence = 0;  // 1, 2, ... per accepted wrench; 0: none yet
  engine::Vec3 F_T_W;          // the force on the tool, expressed in W. Unit: N.
  engine::Vec3 tau_T_W;        // the torque on the handle about the tool point, in W. Unit: N·m.
};

/// How the loop renders the port's robot wrench.
struct RobotWrenchParams {
  /// The force and torque rendered are force_scale times those received (before the layers).
  /// 0 ... 10.
  double force_scale = 1.0;
  /// A wrench not followed by a new one for this long is stale: its force ramps out over the
  /// loop's output ramp (TickConfig::output_ramp_ticks), and ramps back in when wrenches come
  /// again. Counted in the loop's ticks from the tick that first saw it, so lockstep measures it
  /// in stepped time. Unit: s. > 0.
  double stale_s = 0.2;
};

}  // namespace haptic::runtime
