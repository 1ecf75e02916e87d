// The tool on ROS 2-typed topics over real Cyclone DDS on loopback, read as a ROS 2 node's
// middleware (rmw_cyclonedds_cpp) would: a reader of the ROS 2 DDS type name on the "rt/" topic.
// No ROS 2 node takes part (none is installed here): what a node would see is checked field by field.
#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <string>
#include <thread>

#include "federation/dds_participant.hpp"
#include "federation/ros2_topics.hpp"
#include "haptic/dds/ros2.h"

namespace haptic::federation {
namespace {

DomainOptions loopback_domain() {
  DomainOptions options;
  options.domain_id = 100 + static_cast<std::uint32_t>(getpid() % 120);
  options.peers = {"127.0.0.1"};
  return options;
}

/// A reader as a ROS 2 subscription's middleware makes it: the ROS 2 type on "rt/<topic>".
class RosLikeReader {
 public:
  RosLikeReader(const Participant& participant, const dds_topic_descriptor_t* type, const std::string& ros_topic) {
    topic_ = dds_create_topic(participant.handle(), type, dds_topic_of(ros_topic).c_str(), nullptr, nullptr);
    EXPECT_GT(topic_, 0) << dds_error(topic_);
    reader_ = dds_create_reader(participant.handle(), topic_, nullptr, nullptr);
    EXPECT_GT(reader_, 0) << dds_error(reader_);
  }
  ~RosLikeReader() { dds_delete(reader_); }
  std::string type_name() const {
    char name[256] = {};
    dds_get_type_name(topic_, name, sizeof name);
    return name;
  }
  /// Calls f(sample) on the newest valid sample taken, if any (a loan, returned after).
  template <class Sample, class F>
  bool take(F&& f) {
    void* samples[8] = {};
    dds_sample_info_t infos[8];
    const dds_return_t n = dds_take(reader_, samples, infos, 8, 8);
    bool any = false;
    for (dds_return_t i = n - 1; i >= 0 && !any; --i) {
      if (infos[i].valid_data) {
        f(*static_cast<const Sample*>(samples[i]));
        any = true;
      }
    }
    if (n > 0) dds_return_loan(reader_, samples, n);
    return any;
  }

 private:
  dds_entity_t topic_ = 0;
  dds_entity_t reader_ = 0;
};

TEST(Ros2Topics, TheToolArrivesAsPoseTwistWrenchAndJoyUnderRos2sOwnNames) {
  Participant hapticd(loopback_domain());
  Participant node(loopback_domain());
  Ros2Options options;
  options.ros_namespace = "/hapticd/bench/port0";
  options.buttons = 2;
  Ros2ToolPublisher publisher(hapticd, options);
  RosLikeReader pose(node, &geometry_msgs_msg_dds__PoseStamped__desc, "/hapticd/bench/port0/pose");
  RosLikeReader twist(node, &geometry_msgs_msg_dds__TwistStamped__desc, "/hapticd/bench/port0/twist");
  RosLikeReader wrench(node, &geometry_msgs_msg_dds__WrenchStamped__desc, "/hapticd/bench/port0/wrench");
  RosLikeReader joy(node, &sensor_msgs_msg_dds__Joy__desc, "/hapticd/bench/port0/joy");
  EXPECT_EQ(pose.type_name(), "geometry_msgs::msg::dds_::PoseStamped_");
  EXPECT_EQ(wrench.type_name(), "geometry_msgs::msg::dds_::WrenchStamped_");
  EXPECT_EQ(joy.type_name(), "sensor_msgs::msg::dds_::Joy_");

  ToolState tool;
  tool.site = "bench";
  tool.time_ns = 12'345'678'901;  // 12 s and 345678901 ns
  tool.p_WT = {0.01, 0.02, 0.03};
  tool.R_WT = {0.5, 0.5, 0.5, 0.5};  // w, x, y, z
  tool.v_WT = {-0.1, 0.0, 0.2};
  tool.F_T_W = {0.0, 1.5, -2.0};
  tool.buttons = 0b10;
  bool got_pose = false, got_twist = false, got_wrench = false, got_joy = false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!(got_pose && got_twist && got_wrench && got_joy) && std::chrono::steady_clock::now() < deadline) {
    ASSERT_TRUE(publisher.publish(tool)) << publisher.error();
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    got_pose |= pose.take<geometry_msgs_msg_dds__PoseStamped_>([&](const auto& m) {
      EXPECT_EQ(m.header.stamp.sec, 12);
      EXPECT_EQ(m.header.stamp.nanosec, 345678901u);
      EXPECT_STREQ(m.header.frame_id, "hapticd_world");
      EXPECT_EQ(m.pose.position.z, 0.03);
      EXPECT_EQ(m.pose.orientation.w, 0.5);  // ROS's (x, y, z, w), hapticd's (w, x, y, z)
    });
    got_twist |= twist.take<geometry_msgs_msg_dds__TwistStamped_>([&](const auto& m) {
      EXPECT_EQ(m.twist.linear.x, -0.1);
      EXPECT_EQ(m.twist.linear.z, 0.2);
    });
    got_wrench |= wrench.take<geometry_msgs_msg_dds__WrenchStamped_>([&](const auto& m) {
      EXPECT_EQ(m.wrench.force.y, 1.5);
      EXPECT_EQ(m.wrench.force.z, -2.0);
      EXPECT_EQ(m.wrench.torque.x, 0.0);
    });
    got_joy |= joy.take<sensor_msgs_msg_dds__Joy_>([&](const auto& m) {
      ASSERT_EQ(m.buttons._length, 2u);
      EXPECT_EQ(m.buttons._buffer[0], 0);
      EXPECT_EQ(m.buttons._buffer[1], 1);
      EXPECT_EQ(m.axes._length, 0u);
    });
  }
  EXPECT_TRUE(got_pose && got_twist && got_wrench && got_joy)
      << "pose " << got_pose << " twist " << got_twist << " wrench " << got_wrench << " joy " << got_joy;
}

TEST(Ros2Topics, OptionsAreCheckedByName) {
  Ros2Options options;
  EXPECT_EQ(validate(options), "");
  options.ros_namespace = "hapticd";
  EXPECT_NE(validate(options).find("ros_namespace: must be '/'"), std::string::npos);
  options.ros_namespace = "/a//b";
  EXPECT_NE(validate(options).find("ros_namespace"), std::string::npos);
  options.ros_namespace = "/hapticd/port-0";
  EXPECT_NE(validate(options).find("got \"/hapticd/port-0\""), std::string::npos);
  options.ros_namespace = "/hapticd";
  options.buttons = 40;
  EXPECT_EQ(validate(options), "buttons: at most 32, got 40");
  EXPECT_EQ(dds_topic_of("/hapticd/pose"), "rt/hapticd/pose");
}

}  // namespace
}  // namespace haptic::federation
