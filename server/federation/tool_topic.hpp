#pragma once
// The federation's tool topic (proto/haptic/dds/federation.idl, ToolSample): every site publishes
// each of its device ports' tool state at loop rate, and reads the other sites' (docs/federation.md).
// QoS: best effort, keep last one per (site, port), volatile — a tool's state is only worth its
// newest sample, and a late or lost one is never resent.
//
// Off the loop: a sender thread publishes from the loop's sample rings, and a receiver thread
// takes what arrived (Cyclone's write and take may allocate).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <dds/dds.h>

#include "engine/core/vec3.hpp"
#include "federation/dds_endpoint.hpp"

namespace haptic::federation {

/// Topic name in the domain.
inline constexpr const char* kToolTopic = "haptic_federation_tool";

/// What one tool's coupling with another site's tool has sent it, cumulative. Unit: J.
struct CouplingEnergy {
  std::string site;
  std::uint32_t port = 0;
  double sent = 0.0;
};

/// Most couplings a ToolSample carries (the IDL's bound).
inline constexpr std::size_t kMaxCouplings = 8;

/// One site's tool at one tick. Frames and units as TickSample's (W, m, m/s, N).
struct ToolState {
  std::string site;          // the publishing site (at most 64 characters)
  std::uint32_t port = 0;    // its device port
  std::uint64_t tick = 0;
  std::int64_t time_ns = 0;  // its server time at the tick
  engine::Vec3 p_WT;
  engine::Vec3 v_WT;
  engine::Vec3 F_T_W;
  engine::Quat R_WT;
  /// The tool's angular velocity and the torque on it (W; rad/s, N·m), for the ROS 2 topics only
  /// (the tool topic does not carry them); zero on a device without orientation.
  engine::Vec3 w_WT;
  engine::Vec3 tau_T_W;
  std::uint32_t buttons = 0;
  std::vector<CouplingEnergy> energy;  // at most kMaxCouplings
  /// As received: the site its writer speaks for (its partition: under DDS Security the writer's
  /// permissions allow no other, so the identity vouches for it); "" where the writer is in no
  /// single partition. Unset where the transport cannot say (a test's).
  std::optional<std::string> writer_site;
};

/// Publishes this site's tools.
class ToolPublisher {
 public:
  /// In `site`'s partition (in_site_partition): it publishes that site's tools only. Throws
  /// std::runtime_error naming what Cyclone refused.
  ToolPublisher(const Participant& participant, const std::string& site);
  ToolPublisher(const ToolPublisher&) = delete;
  ToolPublisher& operator=(const ToolPublisher&) = delete;

  /// Sends one sample; false (and error() says why) when Cyclone refused it or the site's name
  /// is longer than 64 characters.
  bool publish(const ToolState& tool);
  const std::string& error() const { return error_; }
  /// How many readers of the topic have been matched so far (discovery).
  std::uint32_t matched_readers() const;

 private:
  Endpoint writer_;
  std::string error_;
};

/// Reads the other sites' tools.
class ToolSubscriber {
 public:
  explicit ToolSubscriber(const Participant& participant);
  ToolSubscriber(const ToolSubscriber&) = delete;
  ToolSubscriber& operator=(const ToolSubscriber&) = delete;

  /// Appends every sample of the other sites that arrived since the last take (at most the newest
  /// per tool; this participant's own writers never match: from_other_sites), oldest first, each
  /// with its writer_site; returns how many.
  std::size_t take(std::vector<ToolState>& out);
  std::uint32_t matched_writers() const;

 private:
  Endpoint reader_;
  WriterSites writers_;
};

}  // namespace haptic::federation
