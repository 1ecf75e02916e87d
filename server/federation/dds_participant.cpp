#include "federation/dds_participant.hpp"

#include <stdexcept>

namespace haptic::federation {

namespace {

/// What may go into the XML as a name or address: letters, digits and . : - _ only (an interface
/// name, a host name, an IPv4 or IPv6 address), so no option can inject configuration.
bool plain(const std::string& text) {
  if (text.empty() || text.size() > 253) return false;
  for (const char c : text) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '.' || c == ':' || c == '-' || c == '_';
    if (!ok) return false;
  }
  return true;
}

}  // namespace

std::string validate(const DomainOptions& options) {
  // DDSI's default port mapping (PB 7400, DG 250) leaves room for domains 0 ... 232.
  if (options.domain_id > 232) {
    return "domain_id: must be 0 to 232, got " + std::to_string(options.domain_id);
  }
  if (!plain(options.interface)) {
    return "interface: must be an interface name or address (letters, digits, . : - _), got \"" +
           options.interface + "\"";
  }
  for (std::size_t i = 0; i < options.peers.size(); ++i) {
    if (!plain(options.peers[i])) {
      return "peers[" + std::to_string(i) + "]: must be a host name or address, got \"" + options.peers[i] + "\"";
    }
  }
  return {};
}

std::string cyclone_config(const DomainOptions& options) {
  std::string xml = "<CycloneDDS><Domain id=\"any\"><General><Interfaces><NetworkInterface ";
  const bool address = options.interface.find_first_of(".:") != std::string::npos;
  xml += (address ? "address=\"" : "name=\"") + options.interface + "\"/></Interfaces>";
  xml += options.peers.empty() ? "<AllowMulticast>spdp</AllowMulticast>" : "<AllowMulticast>false</AllowMulticast>";
  xml += "</General>";
  if (!options.peers.empty()) {
    xml += "<Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>20</MaxAutoParticipantIndex><Peers>";
    for (const std::string& peer : options.peers) xml += "<Peer address=\"" + peer + "\"/>";
    xml += "</Peers></Discovery>";
  }
  xml += "</Domain></CycloneDDS>";
  return xml;
}

std::string dds_error(dds_return_t code) { return dds_strretcode(code); }

dds_qos_t* newest_only_qos() {
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_BEST_EFFORT, 0);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 1);
  dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
  return qos;
}

Participant::Participant(const DomainOptions& options) : options_(options) {
  if (std::string error = validate(options); !error.empty()) throw std::runtime_error("federation." + error);
  const std::string config = cyclone_config(options);
  // A domain another participant of this process already made is reused as it is configured.
  const dds_entity_t domain = dds_create_domain(options.domain_id, config.c_str());
  if (domain > 0) {
    domain_ = domain;
  } else if (domain != DDS_RETCODE_PRECONDITION_NOT_MET) {
    throw std::runtime_error("DDS domain " + std::to_string(options.domain_id) + ": " + dds_error(domain) +
                             " (interface \"" + options.interface + "\")");
  }
  participant_ = dds_create_participant(options.domain_id, nullptr, nullptr);
  if (participant_ < 0) {
    const std::string reason = dds_error(participant_);
    if (domain_ > 0) dds_delete(domain_);
    throw std::runtime_error("DDS participant in domain " + std::to_string(options.domain_id) + ": " + reason);
  }
}

Participant::~Participant() {
  if (participant_ > 0) dds_delete(participant_);
  if (domain_ > 0) dds_delete(domain_);
}

}  // namespace haptic::federation
