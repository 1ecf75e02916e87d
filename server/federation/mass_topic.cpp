#include "federation/mass_topic.hpp"

#include <cstring>
#include <stdexcept>

#include "federation/dds_status.hpp"
#include "haptic/dds/federation.h"

namespace haptic::federation {

namespace {

using Sample = haptic_federation_MassSample;

dds_entity_t make_topic(const Participant& participant) {
  const dds_entity_t topic =
      dds_create_topic(participant.handle(), &haptic_federation_MassSample_desc, kMassTopic, nullptr, nullptr);
  if (topic < 0) throw std::runtime_error(std::string("DDS topic ") + kMassTopic + ": " + dds_error(topic));
  return topic;
}

}  // namespace

MassPublisher::MassPublisher(const Participant& participant) : topic_(make_topic(participant)) {
  dds_qos_t* qos = newest_only_qos();
  writer_ = dds_create_writer(participant.handle(), topic_, qos, nullptr);
  dds_delete_qos(qos);
  if (writer_ < 0) throw std::runtime_error(std::string("DDS writer of ") + kMassTopic + ": " + dds_error(writer_));
}

MassPublisher::~MassPublisher() {
  if (writer_ > 0) dds_delete(writer_);
}

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
  haptic_federation_MassCoupling couplings[kMaxMassCouplings]{};
  for (std::size_t i = 0; i < mass.sent.size(); ++i) couplings[i] = {mass.sent[i].first, mass.sent[i].second};
  sample.energy._length = static_cast<std::uint32_t>(mass.sent.size());
  sample.energy._maximum = static_cast<std::uint32_t>(kMaxMassCouplings);
  sample.energy._buffer = couplings;
  sample.energy._release = false;
  const dds_return_t done = dds_write(writer_, &sample);
  if (done != DDS_RETCODE_OK) {
    error_ = "dds_write: " + dds_error(done);
    return false;
  }
  return true;
}

std::uint32_t MassPublisher::matched_readers() const { return matched_count(writer_, true); }

MassSubscriber::MassSubscriber(const Participant& participant) : topic_(make_topic(participant)) {
  dds_qos_t* qos = newest_only_qos();
  reader_ = dds_create_reader(participant.handle(), topic_, qos, nullptr);
  dds_delete_qos(qos);
  if (reader_ < 0) throw std::runtime_error(std::string("DDS reader of ") + kMassTopic + ": " + dds_error(reader_));
}

MassSubscriber::~MassSubscriber() {
  if (reader_ > 0) dds_delete(reader_);
}

std::size_t MassSubscriber::take(std::vector<MassState>& out, const std::string& own_site) {
  std::size_t taken = 0;
  take_each<Sample>(reader_, [&](const Sample& s, const dds_sample_info_t& info) {
    if (!info.valid_data) return;
    MassState mass;
    mass.site.assign(s.site, strnlen(s.site, sizeof s.site));
    if (mass.site == own_site) return;
    mass.mass = s.mass;
    mass.tick = s.tick;
    mass.p_WM = {s.position.x, s.position.y, s.position.z};
    mass.v_WM = {s.velocity.x, s.velocity.y, s.velocity.z};
    for (std::uint32_t k = 0; k < s.energy._length && k < kMaxMassCouplings; ++k) {
      mass.sent.emplace_back(s.energy._buffer[k].site, s.energy._buffer[k].sent);
    }
    out.push_back(std::move(mass));
    ++taken;
  });
  return taken;
}

std::uint32_t MassSubscriber::matched_writers() const { return matched_count(reader_, false); }

}  // namespace haptic::federation
