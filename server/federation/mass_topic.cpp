#include "federation/mass_topic.hpp"

#include <cstring>
#include <stdexcept>

#include "haptic/dds/federation.h"

namespace haptic::federation {

namespace {

using Sample = haptic_federation_MassSample;

}  // namespace

MassPublisher::MassPublisher(const Participant& participant, const std::string& site)
    : writer_(participant, &haptic_federation_MassSample_desc, kMassTopic, Endpoint::Kind::kWriter,
              in_site_partition(newest_only_qos(), site)) {}

bool MassPublisher::publish(const MassState& mass) {
  Sample sample{};
  if (mass.site.empty() || mass.site.size() >= sizeof sample.site) {
    error_ = "site: 1 to 64 characters, got " + std::to_string(mass.site.size());
    return false;
  }
  if (mass.sent.size() > kMaxMassCouplings) {
    error_ = "sent: at most " + std::to_string(kMaxMassCouplings) + " couplings, got " + std::to_string(mass.sent.size());
    return false;
  }
  std::memcpy(sample.site, mass.site.data(), mass.site.size());
  sample.mass = mass.mass;
  sample.tick = mass.tick;
  sample.position = {mass.p_WM.x, mass.p_WM.y, mass.p_WM.z};
  sample.velocity = {mass.v_WM.x, mass.v_WM.y, mass.v_WM.z};
  sample.settled = mass.settled;
  haptic_federation_MassCoupling couplings[kMaxMassCouplings]{};
  for (std::size_t i = 0; i < mass.sent.size(); ++i) couplings[i] = {mass.sent[i].first.value, mass.sent[i].second};
  lend(sample.energy, couplings, mass.sent.size(), kMaxMassCouplings);
  return write_sample(writer_, &sample, error_);
}

std::uint32_t MassPublisher::matched_readers() const { return writer_.matched(); }

MassSubscriber::MassSubscriber(const Participant& participant)
    : reader_(participant, &haptic_federation_MassSample_desc, kMassTopic, Endpoint::Kind::kReader,
              from_other_sites(newest_only_qos())) {}

std::size_t MassSubscriber::take(std::vector<MassState>& out) {
  std::size_t taken = 0;
  take_each<Sample>(reader_.handle(), [&](const Sample& s, const dds_sample_info_t& info) {
    if (!info.valid_data) return;
    MassState mass;
    mass.site.assign(s.site, strnlen(s.site, sizeof s.site));
    mass.mass = s.mass;
    mass.tick = s.tick;
    mass.p_WM = {s.position.x, s.position.y, s.position.z};
    mass.v_WM = {s.velocity.x, s.velocity.y, s.velocity.z};
    mass.settled = s.settled;
    mass.writer_site = writers_.of(reader_.handle(), info.publication_handle);
    for (std::uint32_t k = 0; k < s.energy._length && k < kMaxMassCouplings; ++k) {
      mass.sent.emplace_back(engine::SiteKey{s.energy._buffer[k].site}, s.energy._buffer[k].sent);
    }
    out.push_back(std::move(mass));
    ++taken;
  });
  return taken;
}

std::uint32_t MassSubscriber::matched_writers() const { return reader_.matched(); }

}  // namespace haptic::federation
