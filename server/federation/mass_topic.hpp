#pragma once
// The federation's shared-mass topic (proto/haptic/dds/federation.idl, MassSample): every site
// publishes its copy of each mass shared across sites at loop rate, with what each of its
// couplings sent, and reads the other sites' copies (docs/federation.md, "Shared masses"). QoS as
// the tool topic's: best effort, keep last one per (site, mass), volatile.
//
// Off the loop: the relay's thread publishes and takes.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <dds/dds.h>

#include "engine/core/site_key.hpp"
#include "engine/core/vec3.hpp"
#include "federation/dds_endpoint.hpp"

namespace haptic::federation {

inline constexpr const char* kMassTopic = "haptic_federation_masses";

/// Most couplings a MassSample carries (the IDL's bound).
inline constexpr std::size_t kMaxMassCouplings = 8;

/// One site's copy of one shared mass at one tick. W frame; m, m/s, J.
struct MassState {
  std::string site;           // the publishing site (at most 64 characters)
  std::uint64_t mass = 0;     // engine::shared_mass_key
  std::uint64_t tick = 0;
  engine::Vec3 p_WM;
  engine::Vec3 v_WM;
  /// (other site's key, cumulative energy its coupling with this copy sent it); at most
  /// kMaxMassCouplings.
  std::vector<std::pair<engine::SiteKey, double>> sent;
  /// The copy has its place (runtime::LocalMassCopy::settled).
  bool settled = true;
  /// As received: the site its writer speaks for (ToolState::writer_site).
  std::optional<std::string> writer_site;
};

class MassPublisher {
 public:
  /// In `site`'s partition (in_site_partition). Throws std::runtime_error naming what Cyclone
  /// refused.
  MassPublisher(const Participant& participant, const std::string& site);
  MassPublisher(const MassPublisher&) = delete;
  MassPublisher& operator=(const MassPublisher&) = delete;

  /// Sends one sample; false (and error() says why) when refused.
  bool publish(const MassState& mass);
  const std::string& error() const { return error_; }
  std::uint32_t matched_readers() const;

 private:
  Endpoint writer_;
  std::string error_;
};

class MassSubscriber {
 public:
  explicit MassSubscriber(const Participant& participant);
  MassSubscriber(const MassSubscriber&) = delete;
  MassSubscriber& operator=(const MassSubscriber&) = delete;

  /// Appends every sample of the other sites that arrived since the last take (this participant's
  /// own writers never match: from_other_sites), oldest first, each with its writer_site; returns
  /// how many.
  std::size_t take(std::vector<MassState>& out);
  std::uint32_t matched_writers() const;

 private:
  Endpoint reader_;
  WriterSites writers_;
};

}  // namespace haptic::federation
