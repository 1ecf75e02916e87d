#include "federation/ros2_topics.hpp"

#include <cmath>
#include <cstring>
#include <ctime>
#include <stdexcept>
#include <vector>

#include "federation/dds_endpoint.hpp"
#include "haptic/dds/ros2.h"

namespace haptic::federation {

namespace {

enum Topic { kPose, kTwist, kWrench, kJoy };

struct TopicKind {
  const char* suffix;
  const dds_topic_descriptor_t* type;
};
const TopicKind kTopics[] = {{kRos2PublishedTopics[kPose], &geometry_msgs_msg_dds__PoseStamped__desc},
                             {kRos2PublishedTopics[kTwist], &geometry_msgs_msg_dds__TwistStamped__desc},
                             {kRos2PublishedTopics[kWrench], &geometry_msgs_msg_dds__WrenchStamped__desc},
                             {kRos2PublishedTopics[kJoy], &sensor_msgs_msg_dds__Joy__desc}};

/// The header: stamped at `stamp_ns` (ns since the clock's epoch), in `frame_id`.
std_msgs_msg_dds__Header_ header(std::int64_t stamp_ns, const std::string& frame_id) {
  std_msgs_msg_dds__Header_ out{};
  // builtin_interfaces/Time: seconds and nanoseconds in [0, 1e9), for negative times too.
  std::int64_t sec = stamp_ns / 1'000'000'000;
  std::int64_t nanosec = stamp_ns % 1'000'000'000;
  if (nanosec < 0) {
    nanosec += 1'000'000'000;
    --sec;
  }
  out.stamp.sec = static_cast<int32_t>(sec);
  out.stamp.nanosec = static_cast<uint32_t>(nanosec);
  out.frame_id = const_cast<char*>(frame_id.c_str());  // written, never freed: the writer copies
  return out;
}

geometry_msgs_msg_dds__Vector3_ vector(const engine::Vec3& v) { return {v.x, v.y, v.z}; }

std::int64_t wall_clock_ns() {
  timespec now{};
  clock_gettime(CLOCK_REALTIME, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

}  // namespace

std::string dds_topic_of(const std::string& ros_topic) { return "rt" + ros_topic; }

Ros2ToolPublisher::Ros2ToolPublisher(const Participant& participant, const Ros2Options& options)
    : options_(options) {
  if (std::string error = validate(options); !error.empty()) throw std::runtime_error("ros2." + error);
  for (int i = 0; i < 4; ++i) {  // one that cannot be made throws, and those made before are deleted
    const std::string name = dds_topic_of(options.ros_namespace + kTopics[i].suffix);
    writers_[i] = std::make_unique<Endpoint>(participant, kTopics[i].type, name.c_str(), Endpoint::Kind::kWriter,
                                             ros2_publisher_qos());
  }
}

Ros2ToolPublisher::~Ros2ToolPublisher() = default;

bool Ros2ToolPublisher::publish(const ToolState& tool) {
  const std_msgs_msg_dds__Header_ stamp =
      header(options_.stamp_clock == Ros2Options::StampClock::kServerTime ? tool.time_ns : wall_clock_ns(),
             options_.frame_id);
  geometry_msgs_msg_dds__PoseStamped_ pose{};
  pose.header = stamp;
  pose.pose.position = {tool.p_WT.x, tool.p_WT.y, tool.p_WT.z};
  pose.pose.orientation = {tool.R_WT.x, tool.R_WT.y, tool.R_WT.z, tool.R_WT.w};  // ROS: x, y, z, w
  geometry_msgs_msg_dds__TwistStamped_ twist{};
  twist.header = stamp;
  twist.twist.linear = vector(tool.v_WT);
  twist.twist.angular = vector(tool.w_WT);
  geometry_msgs_msg_dds__WrenchStamped_ wrench{};
  wrench.header = stamp;
  wrench.wrench.force = vector(tool.F_T_W);
  wrench.wrench.torque = vector(tool.tau_T_W);
  int32_t pressed[32] = {};
  for (std::uint32_t b = 0; b < options_.buttons; ++b) pressed[b] = (tool.buttons >> b) & 1u;
  sensor_msgs_msg_dds__Joy_ joy{};
  joy.header = stamp;
  joy.buttons._length = options_.buttons;
  joy.buttons._maximum = options_.buttons;
  joy.buttons._buffer = pressed;
  joy.buttons._release = false;
  const void* messages[4] = {&pose, &twist, &wrench, &joy};
  for (int i = 0; i < 4; ++i) {
    if (!write_sample(*writers_[i], messages[i], error_)) {
      error_ = std::string(kTopics[i].suffix) + ": " + error_;
      return false;
    }
  }
  return true;
}

std::uint32_t Ros2ToolPublisher::matched_readers() const { return writers_[kPose]->matched(); }

Ros2WrenchSubscriber::Ros2WrenchSubscriber(const Participant& participant, const std::string& ros_topic,
                                           const std::string& frame_id)
    : ros_topic_(ros_topic),
      frame_id_(frame_id),
      // best effort: matches a reliable or a best-effort node
      reader_(participant, &geometry_msgs_msg_dds__WrenchStamped__desc, dds_topic_of(ros_topic).c_str(),
              Endpoint::Kind::kReader, newest_only_qos()) {}

Ros2WrenchSubscriber::~Ros2WrenchSubscriber() = default;

WrenchTaken Ros2WrenchSubscriber::take() {
  WrenchTaken out;
  using Sample = geometry_msgs_msg_dds__WrenchStamped_;
  take_each<Sample>(reader_.handle(), [&](const Sample& s, const dds_sample_info_t& info) {
    if (!info.valid_data) return;
    const char* frame = s.header.frame_id != nullptr ? s.header.frame_id : "";
    if (std::strcmp(frame, frame_id_.c_str()) != 0) {
      ++out.wrong_frame;
      out.refused_frame = frame;
      return;
    }
    const geometry_msgs_msg_dds__Wrench_& w = s.wrench;
    const double values[6] = {w.force.x, w.force.y, w.force.z, w.torque.x, w.torque.y, w.torque.z};
    for (const double v : values) {
      if (!std::isfinite(v)) {
        ++out.not_finite;
        return;
      }
    }
    out.accepted = true;
    out.F_T_W = {w.force.x, w.force.y, w.force.z};
    out.tau_T_W = {w.torque.x, w.torque.y, w.torque.z};
  });
  return out;
}

std::uint32_t Ros2WrenchSubscriber::matched_writers() const { return reader_.matched(); }

}  // namespace haptic::federation
