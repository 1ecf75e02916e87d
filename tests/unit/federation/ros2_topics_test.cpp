// The tool on ROS 2-typed topics over real Cyclone DDS on loopback, read as a ROS 2 node's
// middleware (rmw_cyclonedds_cpp) would: a reader of the ROS 2 DDS type name on the "rt/" topic.
// No ROS 2 node takes part (none is installed here): what a node would see is checked field by field.
#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "federation/dds_participant.hpp"
#include "federation/ros2_topics.hpp"
#include "federation/sample_relay.hpp"
#include "haptic/dds/ros2.h"
#include "support/loopback_dds.hpp"

namespace haptic::federation {
namespace {

using test::loopback_domain;

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
  options.stamp_clock = Ros2Options::StampClock::kServerTime;  // the tick's own stamp, exactly
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
  tool.w_WT = {0.0, 3.0, 0.0};      // a turning handle (6-DOF)
  tool.tau_T_W = {0.0, 0.0, 0.25};  // and the torque on it
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
      EXPECT_EQ(m.twist.angular.y, 3.0);
    });
    got_wrench |= wrench.take<geometry_msgs_msg_dds__WrenchStamped_>([&](const auto& m) {
      EXPECT_EQ(m.wrench.force.y, 1.5);
      EXPECT_EQ(m.wrench.force.z, -2.0);
      EXPECT_EQ(m.wrench.torque.x, 0.0);
      EXPECT_EQ(m.wrench.torque.z, 0.25);
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
  options.buttons = 0;
  options.wrench_topic = "wrench_command";
  EXPECT_EQ(validate(options), "");
  options.wrench_topic = "robot/wrench_command";
  EXPECT_EQ(validate(options), "");
  options.wrench_topic = "/wrench_command";
  EXPECT_NE(validate(options).find("wrench_topic: must be names"), std::string::npos);
  options.wrench_topic = "wrench";  // hapticd's own: it would feel its own force back
  EXPECT_EQ(validate(options), "wrench_topic: \"wrench\" is one hapticd publishes");
  EXPECT_EQ(dds_topic_of("/hapticd/pose"), "rt/hapticd/pose");
}

/// A ROS 2 publisher as its middleware makes it: the ROS 2 type on "rt/<topic>", with ROS 2's
/// default QoS (reliable, keep last 10, volatile).
class RosLikeWrenchWriter {
 public:
  RosLikeWrenchWriter(const Participant& participant, const std::string& ros_topic) {
    topic_ = dds_create_topic(participant.handle(), &geometry_msgs_msg_dds__WrenchStamped__desc,
                              dds_topic_of(ros_topic).c_str(), nullptr, nullptr);
    EXPECT_GT(topic_, 0) << dds_error(topic_);
    dds_qos_t* qos = dds_create_qos();
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
    dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 10);
    writer_ = dds_create_writer(participant.handle(), topic_, qos, nullptr);
    dds_delete_qos(qos);
    EXPECT_GT(writer_, 0) << dds_error(writer_);
  }
  ~RosLikeWrenchWriter() { dds_delete(writer_); }
  void write(const char* frame_id, double fx, double fy, double fz, double tx = 0.0) {
    geometry_msgs_msg_dds__WrenchStamped_ m{};
    m.header.stamp.sec = 7;
    m.header.frame_id = const_cast<char*>(frame_id);
    m.wrench.force = {fx, fy, fz};
    m.wrench.torque = {tx, 0.0, 0.0};
    ASSERT_EQ(dds_write(writer_, &m), DDS_RETCODE_OK);
  }
  std::uint32_t matched() const {
    dds_publication_matched_status_t status{};
    return dds_get_publication_matched_status(writer_, &status) == DDS_RETCODE_OK ? status.current_count : 0;
  }

 private:
  dds_entity_t topic_ = 0;
  dds_entity_t writer_ = 0;
};

/// Writes with `write` until `arrived` says it came (discovery may be late), bounded: 10 s.
template <class Write, class Arrived>
bool until_arrived(Write&& write, Arrived&& arrived) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (std::chrono::steady_clock::now() < deadline) {
    write();
    for (int i = 0; i < 10; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      if (arrived()) return true;
    }
  }
  return false;
}

TEST(Ros2Topics, AWrenchFromARos2PublisherIsTakenInItsFrameOnly) {
  Participant hapticd(loopback_domain());
  Participant node(loopback_domain());
  Ros2WrenchSubscriber subscriber(hapticd, "/hapticd/bench/port0/wrench_command", "hapticd_world");
  RosLikeWrenchWriter writer(node, "/hapticd/bench/port0/wrench_command");

  WrenchTaken taken;
  ASSERT_TRUE(until_arrived([&] { writer.write("hapticd_world", 1.0, -2.0, 3.5, 0.25); },
                            [&] { return (taken = subscriber.take()).accepted; }));
  EXPECT_EQ(taken.F_T_W, (engine::Vec3{1.0, -2.0, 3.5}));
  EXPECT_EQ(taken.tau_T_W, (engine::Vec3{0.25, 0.0, 0.0}));
  EXPECT_EQ(subscriber.matched_writers(), 1u);

  ASSERT_TRUE(until_arrived([&] { writer.write("tool0", 1.0, 0.0, 0.0); },
                            [&] { return (taken = subscriber.take()).wrong_frame > 0; }));
  EXPECT_FALSE(taken.accepted);
  EXPECT_EQ(taken.refused_frame, "tool0");

  const double nan = std::numeric_limits<double>::quiet_NaN();
  ASSERT_TRUE(until_arrived([&] { writer.write("hapticd_world", 0.0, nan, 0.0); },
                            [&] { return (taken = subscriber.take()).not_finite > 0; }));
  EXPECT_FALSE(taken.accepted);
  ASSERT_TRUE(until_arrived([&] { writer.write("hapticd_world", 0.0, 0.0, 0.0, std::numeric_limits<double>::infinity()); },
                            [&] { return (taken = subscriber.take()).not_finite > 0; }));
  EXPECT_FALSE(taken.accepted);
}

// The relay, as hapticd runs it: each port's wrench topic under its namespace, accepted wrenches
// into the port's mailbox (a new sequence each), refused ones counted and logged once per reason.
TEST(Ros2Topics, TheRelayPutsAPortsWrenchInItsMailboxAndRefusesTheRest) {
  RelayOptions options;
  options.site = "bench";
  options.domain = loopback_domain();
  options.tools = false;
  options.ros2 = Ros2Options{};
  options.ros2->ros_namespace = "/hapticd/bench";
  options.ros2->wrench_topic = "wrench_command";
  std::mutex mutex;
  std::vector<std::string> lines;
  options.log = [&](const std::string& line) {
    const std::lock_guard<std::mutex> lock(mutex);
    lines.push_back(line);
  };
  runtime::SampleRing samples[2];
  runtime::LatestValue<runtime::RobotWrench> mailbox[2];
  SampleRelay relay(options, {RelayPort{&samples[0], 0, nullptr, nullptr, &mailbox[0]},
                              RelayPort{&samples[1], 0, nullptr, nullptr, &mailbox[1]}});
  relay.start();
  Participant node(loopback_domain());
  RosLikeWrenchWriter port1(node, "/hapticd/bench/port1/wrench_command");

  ASSERT_TRUE(until_arrived([&] { port1.write("hapticd_world", 0.0, 0.0, -4.0); },
                            [&] { return mailbox[1].load().sequence > 0; }));
  const runtime::RobotWrench got = mailbox[1].load();
  EXPECT_EQ(got.F_T_W, (engine::Vec3{0.0, 0.0, -4.0}));
  EXPECT_EQ(mailbox[0].load().sequence, 0u) << "port 1's wrench reached port 0";

  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto logged = [&] {
    const std::lock_guard<std::mutex> lock(mutex);
    return lines.size();
  };
  ASSERT_TRUE(until_arrived([&] { port1.write("hapticd_world", nan, 0.0, 0.0); }, [&] { return logged() >= 1; }));
  ASSERT_TRUE(until_arrived([&] { port1.write("base_link", 1.0, 0.0, 0.0); }, [&] { return logged() >= 2; }));
  // More of both: counted, not logged again.
  const std::uint64_t refused = relay.wrenches_refused();
  ASSERT_TRUE(until_arrived(
      [&] {
        port1.write("hapticd_world", nan, 0.0, 0.0);
        port1.write("base_link", 1.0, 0.0, 0.0);
      },
      [&] { return relay.wrenches_refused() >= refused + 4; }));
  relay.stop();
  const runtime::RobotWrench after = mailbox[1].load();
  EXPECT_EQ(after.F_T_W, got.F_T_W) << "a refused wrench reached the mailbox";
  EXPECT_GE(relay.wrenches_accepted(), 1u);
  const std::lock_guard<std::mutex> lock(mutex);
  ASSERT_EQ(lines.size(), 2u) << "each reason logged once";
  EXPECT_NE(lines[0].find("/hapticd/bench/port1/wrench_command with a NaN or an infinity refused"), std::string::npos)
      << lines[0];
  EXPECT_NE(lines[1].find("in frame \"base_link\" refused: it must be in \"hapticd_world\""), std::string::npos)
      << lines[1];
}

}  // namespace
}  // namespace haptic::federation
