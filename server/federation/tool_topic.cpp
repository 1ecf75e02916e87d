#include "federation/tool_topic.hpp"

#include <array>
#include <cstring>
#include <stdexcept>

#include "haptic/dds/federation.h"

namespace haptic::federation {

namespace {

using Sample = haptic_federation_ToolSample;

haptic_federation_Vec3 to_dds(const engine::Vec3& v) { return {v.x, v.y, v.z}; }
engine::Vec3 from_dds(const haptic_federation_Vec3& v) { return {v.x, v.y, v.z}; }

}  // namespace

ToolPublisher::ToolPublisher(const Participant& participant, const std::string& site)
    : writer_(participant, &haptic_federation_ToolSample_desc, kToolTopic, Endpoint::Kind::kWriter,
              in_site_partition(newest_only_qos(), site)) {}

bool ToolPublisher::publish(const ToolState& tool) {
  Sample sample{};
  if (tool.site.size() >= sizeof sample.site) {
    error_ = "site: at most 64 characters, got " + std::to_string(tool.site.size());
    return false;
  }
  std::memcpy(sample.site, tool.site.data(), tool.site.size());
  sample.port = tool.port;
  sample.tick = tool.tick;
  sample.time_ns = tool.time_ns;
  sample.position = to_dds(tool.p_WT);
  sample.velocity = to_dds(tool.v_WT);
  sample.force = to_dds(tool.F_T_W);
  sample.orientation = {tool.R_WT.w, tool.R_WT.x, tool.R_WT.y, tool.R_WT.z};
  sample.buttons = tool.buttons;
  if (tool.energy.size() > kMaxCouplings) {
    error_ = "energy: at most " + std::to_string(kMaxCouplings) + " couplings, got " + std::to_string(tool.energy.size());
    return false;
  }
  haptic_federation_CouplingEnergy couplings[kMaxCouplings]{};
  for (std::size_t i = 0; i < tool.energy.size(); ++i) {
    const CouplingEnergy& e = tool.energy[i];
    if (e.site.size() >= sizeof couplings[i].site) {
      error_ = "energy[" + std::to_string(i) + "].site: at most 64 characters";
      return false;
    }
    std::memcpy(couplings[i].site, e.site.data(), e.site.size());
    couplings[i].port = e.port;
    couplings[i].sent = e.sent;
  }
  lend(sample.energy, couplings, tool.energy.size(), kMaxCouplings);
  return write_sample(writer_, &sample, error_);
}

std::uint32_t ToolPublisher::matched_readers() const { return writer_.matched(); }

ToolSubscriber::ToolSubscriber(const Participant& participant)
    : reader_(participant, &haptic_federation_ToolSample_desc, kToolTopic, Endpoint::Kind::kReader,
              from_other_sites(newest_only_qos())) {}

std::size_t ToolSubscriber::take(std::vector<ToolState>& out) {
  std::size_t taken = 0;
  take_each<Sample>(reader_.handle(), [&](const Sample& s, const dds_sample_info_t& info) {
    if (!info.valid_data) return;
    ToolState tool;
    tool.site.assign(s.site, strnlen(s.site, sizeof s.site));
    tool.port = s.port;
    tool.tick = s.tick;
    tool.time_ns = s.time_ns;
    tool.p_WT = from_dds(s.position);
    tool.v_WT = from_dds(s.velocity);
    tool.F_T_W = from_dds(s.force);
    tool.R_WT = {s.orientation.w, s.orientation.x, s.orientation.y, s.orientation.z};
    tool.buttons = s.buttons;
    tool.writer_site = writers_.of(reader_.handle(), info.publication_handle);
    for (std::uint32_t k = 0; k < s.energy._length && k < kMaxCouplings; ++k) {
      const haptic_federation_CouplingEnergy& e = s.energy._buffer[k];
      tool.energy.push_back({std::string(e.site, strnlen(e.site, sizeof e.site)), e.port, e.sent});
    }
    out.push_back(std::move(tool));
    ++taken;
  });
  return taken;
}

std::uint32_t ToolSubscriber::matched_writers() const { return reader_.matched(); }

}  // namespace haptic::federation
