#include "federation/dds_endpoint.hpp"

#include <stdexcept>
#include <string>

namespace haptic::federation {

Endpoint::Endpoint(const Participant& participant, const dds_topic_descriptor_t* type, const char* topic, Kind kind,
                   dds_qos_t* qos)
    : kind_(kind) {
  topic_ = dds_create_topic(participant.handle(), type, topic, nullptr, nullptr);
  if (topic_ < 0) {
    dds_delete_qos(qos);
    throw std::runtime_error(std::string("DDS topic ") + topic + ": " + dds_error(topic_));
  }
  entity_ = kind == Kind::kWriter ? dds_create_writer(participant.handle(), topic_, qos, nullptr)
                                  : dds_create_reader(participant.handle(), topic_, qos, nullptr);
  dds_delete_qos(qos);
  if (entity_ < 0) {
    throw std::runtime_error(std::string("DDS ") + (kind == Kind::kWriter ? "writer of " : "reader of ") + topic +
                             ": " + dds_error(entity_));
  }
}

const std::string& WriterSites::of(dds_entity_t reader, dds_instance_handle_t writer) {
  if (const auto it = known_.find(writer); it != known_.end()) return it->second;
  if (known_.size() >= 256) known_.clear();  // writers come and go over a long run: forget the old
  std::string site;
  if (dds_builtintopic_endpoint_t* endpoint = dds_get_matched_publication_data(reader, writer)) {
    std::uint32_t count = 0;
    char** names = nullptr;
    if (endpoint->qos != nullptr && dds_qget_partition(endpoint->qos, &count, &names)) {
      if (count == 1 && names[0] != nullptr) site = names[0];
      for (std::uint32_t i = 0; i < count; ++i) dds_free(names[i]);
      dds_free(names);
    }
    dds_builtintopic_free_endpoint(endpoint);
  } else {
    static const std::string unknown;  // not matched (any more): not kept, asked again next time
    return unknown;
  }
  return known_.emplace(writer, std::move(site)).first->second;
}

Endpoint::~Endpoint() {
  if (entity_ > 0) dds_delete(entity_);
}

}  // namespace haptic::federation
