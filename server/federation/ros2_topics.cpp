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

/// The publishers' QoS: reliable, so that a ROS 2 subscriber with the default profile (reliable,
/// keep last 10) matches as well as one with the sensor-data profile (best effort); keep last 1,
/// so that the writer never waits on a slow reader (history replaces what was not yet taken);
/// volatile, as ROS 2's default.
dds_qos_t* publisher_qos() {
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(1));
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 1);
  dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
  return qos;
}

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
  dds_qos_t* qos = publisher_qos();
  for (int i = 0; i < 4; ++i) {
    const std::string name = dds_topic_of(options.ros_namespace + kTopics[i].suffix);
    const dds_entity_t topic = dds_create_topic(participant.handle(), kTopics[i].type, name.c_str(), nullptr, nullptr);
    writers_[i] = topic < 0 ? topic : dds_create_writer(participant.handle(), topic, qos, nullptr);
    if (writers_[i] < 0) {
      const std::string reason = dds_error(writers_[i]);
      dds_delete_qos(qos);
      throw std::runtime_error("DDS topic " + name + ": " + reason);
    }
  }
  dds_delete_qos(qos);
}

Ros2ToolPublisher::~Ros2ToolPublisher() {
  for (const dds_entity_t writer : writers_) {
    if (writer > 0) dds_delete(writer);
  }
}

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
    const dds_return_t done = dds_write(writers_[i], messages[i]);
    if (done != DDS_RETCODE_OK) {
      error_ = std::string("dds_write on ") + kTopics[i].suffix + ": " + dds_error(done);
      return false;
    }
  }
  return true;
}

std::uint32_t Ros2ToolPublisher::matched_readers() const {
  dds_publication_matched_status_t status{};
  return dds_get_publication_matched_status(writers_[kPose], &status) == DDS_RETCODE_OK ? status.current_count : 0;
}

Ros2WrenchSubscriber::Ros2WrenchSubscriber(const Participant& participant, const std::string& ros_topic,
                                           const std::string& frame_id)
    : ros_topic_(ros_topic), frame_id_(frame_id) {
  const std::string name = dds_topic_of(ros_topic);
  topic_ = dds_create_topic(participant.handle(), &geometry_msgs_msg_dds__WrenchStamped__desc, name.c_str(), nullptr,
                            nullptr);
  dds_qos_t* qos = newest_only_qos();  // best effort: matches a reliable or a best-effort node
  reader_ = topic_ < 0 ? topic_ : dds_create_reader(participant.handle(), topic_, qos, nullptr);
  dds_delete_qos(qos);
  if (reader_ < 0) throw std::runtime_error("DDS reader of " + name + ": " + dds_error(reader_));
}

Ros2WrenchSubscriber::~Ros2WrenchSubscriber() {
  if (reader_ > 0) dds_delete(reader_);
}

WrenchTaken Ros2WrenchSubscriber::take() {
  WrenchTaken out;
  using Sample = geometry_msgs_msg_dds__WrenchStamped_;
  take_each<Sample>(reader_, [&](const Sample& s, const dds_sample_info_t& info) {
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

std::uint32_t Ros2WrenchSubscriber::matched_writers() const { return matched_count(reader_, false); }

}  // namespace haptic::federation
