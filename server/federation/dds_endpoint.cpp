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

Endpoint::~Endpoint() {
  if (entity_ > 0) dds_delete(entity_);
}

}  // namespace haptic::federation
