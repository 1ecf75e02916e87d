#pragma once
// A device's tool on ROS 2 topics without a ROS install (docs/federation.md, "ROS 2"): the types
// of proto/haptic/dds/ros2.idl (ROS 2's own names on DDS) on topics named as ROS 2's middleware
// names them ("rt/" + the ROS topic), so a ROS 2 node on rmw_cyclonedds_cpp in the same DDS domain
// subscribes to them as to any node's:
//   <namespace>/pose    geometry_msgs/msg/PoseStamped   p_WT (m) and R_WT
//   <namespace>/twist   geometry_msgs/msg/TwistStamped  v_WT (m/s); angular 0 (not published yet)
//   <namespace>/wrench  geometry_msgs/msg/WrenchStamped F_T_W (N), the force on the tool; torque 0
//   <namespace>/joy     sensor_msgs/msg/Joy             the buttons, 1 pressed (no axes)
// QoS as ROS 2's sensor-data profile: best effort, keep last 1, volatile.
// Off the loop (Cyclone's write may allocate): a sender thread publishes at the configured rate.

#include <string>

#include <dds/dds.h>

#include "federation/dds_participant.hpp"
#include "federation/tool_topic.hpp"

namespace haptic::federation {

struct Ros2Options {
  /// The ROS namespace of the topics, "/hapticd/<site>/port0" say: a leading '/', then names of
  /// letters, digits and '_' separated by '/'.
  std::string ros_namespace = "/hapticd";
  std::string frame_id = "hapticd_world";  // header.frame_id: the device's W
  std::uint32_t buttons = 0;               // how many buttons Joy reports
};

/// "" or one message naming the bad option.
std::string validate(const Ros2Options& options);

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
  dds_entity_t writers_[4] = {0, 0, 0, 0};  // pose, twist, wrench, joy
  std::string error_;
};

}  // namespace haptic::federation
