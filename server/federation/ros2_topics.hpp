#pragma once
// A device's tool on ROS 2 topics without a ROS install (docs/federation.md, "ROS 2"): the types
// of proto/haptic/dds/ros2.idl (ROS 2's own names on DDS) on topics named as ROS 2's middleware
// names them ("rt/" + the ROS topic), so a ROS 2 node on rmw_cyclonedds_cpp in the same DDS domain
// subscribes to them as to any node's:
//   <namespace>/pose    geometry_msgs/msg/PoseStamped   p_WT (m) and R_WT
//   <namespace>/twist   geometry_msgs/msg/TwistStamped  v_WT (m/s); angular 0 (not published yet)
//   <namespace>/wrench  geometry_msgs/msg/WrenchStamped F_T_W (N), the force on the tool; torque 0
//   <namespace>/joy     sensor_msgs/msg/Joy             the buttons, 1 pressed (no axes)
// QoS: ros2_publisher_qos (dds_qos.hpp: reliable, keep last 1, volatile), which a node with the
// default profile or the sensor-data one matches.
// Off the loop (Cyclone's write may allocate): a sender thread publishes at the configured rate.
//
// And, where configured, one topic a ROS 2 node publishes to (Ros2WrenchSubscriber):
//   <namespace>/<wrench_topic>  geometry_msgs/msg/WrenchStamped  F_T_W (N), the force the node
//                               asks for on the tool (a robot's measured wrench, say), and tau_T_W
//                               (N·m), the torque on the handle about the tool point
// which a node publishes as to any ROS 2 topic, e.g. with the default name:
//   ros2 topic pub -r 100 /hapticd/lab_a/port0/wrench_command geometry_msgs/msg/WrenchStamped
//     "{header: {frame_id: hapticd_world}, wrench: {force: {x: 0.0, y: 0.0, z: 2.0}}}"
// (one command line).
// Its reader is best effort (keep last 1), so it matches a node's reliable or best-effort writer.

#include <cstdint>
#include <memory>
#include <string>

#include <dds/dds.h>

#include "engine/core/vec3.hpp"
#include "federation/dds_endpoint.hpp"
#include "federation/dds_participant.hpp"
#include "federation/options.hpp"
#include "federation/tool_topic.hpp"

namespace haptic::federation {

/// The DDS topic name of a ROS 2 topic: "rt" + the ROS name ("/hapticd/pose" → "rt/hapticd/pose").
std::string dds_topic_of(const std::string& ros_topic);

class Ros2ToolPublisher {
 public:
  /// Throws std::runtime_error naming the bad option or what Cyclone refused.
  Ros2ToolPublisher(const Participant& participant, const Ros2Options& options);
  ~Ros2ToolPublisher();
  Ros2ToolPublisher(const Ros2ToolPublisher&) = delete;
  Ros2ToolPublisher& operator=(const Ros2ToolPublisher&) = delete;

  /// Publishes the tool on the four topics, stamped with its server time; false and error()
  /// when Cyclone refused one.
  bool publish(const ToolState& tool);
  const std::string& error() const { return error_; }
  /// Readers matched on the pose topic so far.
  std::uint32_t matched_readers() const;

 private:
  Ros2Options options_;
  std::unique_ptr<Endpoint> writers_[4];  // pose, twist, wrench, joy
  std::string error_;
};

/// What one Ros2WrenchSubscriber::take found.
struct WrenchTaken {
  bool accepted = false;       // a wrench was accepted: the newest one's force and torque below
  engine::Vec3 F_T_W;          // Unit: N, in W (header.frame_id).
  engine::Vec3 tau_T_W;        // Unit: N·m.
  std::uint32_t wrong_frame = 0;  // refused: header.frame_id is not the configured frame_id
  std::uint32_t not_finite = 0;   // refused: a NaN or infinite force or torque component
  std::string refused_frame;      // the frame_id of the last one refused for its frame
};

/// A ROS 2 node's geometry_msgs/msg/WrenchStamped for the tool, read as ROS 2's middleware writes
/// it (the ROS 2 type on "rt/" + the ROS topic). A wrench whose header.frame_id is not frame_id
/// (the W hapticd publishes in) is refused: hapticd does not transform between frames; so is one
/// with a NaN or infinite component. Off the loop.
class Ros2WrenchSubscriber {
 public:
  /// ros_topic: the full ROS name ("/hapticd/lab_a/port0/wrench_command"). Throws
  /// std::runtime_error naming the topic and what Cyclone refused.
  Ros2WrenchSubscriber(const Participant& participant, const std::string& ros_topic, const std::string& frame_id);
  ~Ros2WrenchSubscriber();
  Ros2WrenchSubscriber(const Ros2WrenchSubscriber&) = delete;
  Ros2WrenchSubscriber& operator=(const Ros2WrenchSubscriber&) = delete;

  /// Takes every wrench that arrived; the newest accepted one wins.
  WrenchTaken take();
  /// Writers (ROS 2 publishers) matched so far.
  std::uint32_t matched_writers() const;
  const std::string& ros_topic() const { return ros_topic_; }

 private:
  std::string ros_topic_;
  std::string frame_id_;
  Endpoint reader_;
};

}  // namespace haptic::federation
