#pragma once
// Carries the loop's tick samples to DDS at a configured rate (docs/federation.md): on a thread
// of its own, every period it reads each device port's newest sample from its SampleRing and, when
// the port has ticked since, publishes it — as ROS 2 topics (ros2_topics) where configured. The
// loop never waits on it, and a sample nobody asked for is never converted.

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "federation/dds_participant.hpp"
#include "federation/ros2_topics.hpp"
#include "runtime/sample_ring.hpp"

namespace haptic::federation {

struct RelayOptions {
  std::string site;                 // this site's name (1 ... 64 characters)
  DomainOptions domain;
  std::optional<Ros2Options> ros2;  // ros2.ros_namespace is the site's; ports add "/port<N>"
  double rate_hz = 100.0;           // publications per second, per port. Unit: Hz.
};

/// One port's ring and the buttons its device reports.
struct RelayPort {
  const runtime::SampleRing* samples = nullptr;
  std::uint32_t buttons = 0;
};

class SampleRelay {
 public:
  /// Joins the domain and makes the writers (off the loop). Throws std::runtime_error naming what
  /// was refused.
  SampleRelay(const RelayOptions& options, const std::vector<RelayPort>& ports);
  ~SampleRelay();
  SampleRelay(const SampleRelay&) = delete;
  SampleRelay& operator=(const SampleRelay&) = delete;

  void start();
  void stop();
  /// Samples published so far (all ports), and publications DDS refused.
  std::uint64_t published() const { return published_.load(std::memory_order_relaxed); }
  std::uint64_t failed() const { return failed_.load(std::memory_order_relaxed); }

 private:
  void run();

  RelayOptions options_;
  std::vector<RelayPort> ports_;
  std::unique_ptr<Participant> participant_;
  std::vector<std::unique_ptr<Ros2ToolPublisher>> ros2_;  // per port, when configured
  std::vector<std::uint64_t> last_tick_;                  // per port: the newest tick published
  std::thread thread_;
  std::atomic<bool> stopping_{false};
  std::atomic<std::uint64_t> published_{0};
  std::atomic<std::uint64_t> failed_{0};
};

}  // namespace haptic::federation
