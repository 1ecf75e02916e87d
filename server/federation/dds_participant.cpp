#include "federation/dds_participant.hpp"

#include <stdexcept>

static_assert(haptic::federation::kDdsDomainDefault == DDS_DOMAIN_DEFAULT,
              "options.hpp's DDS_DOMAIN_DEFAULT is dds/dds.h's");

namespace haptic::federation {

namespace {

/// The Library element of one plugin: a full path when the plugins' folder is known (Debian's
/// is off the loader's search path, and Cyclone loads a plugin with dlopen), else the name
/// Cyclone searches for.
std::string plugin_library(const char* name, const char* init, const char* finalize) {
  const std::string dir = security_plugin_dir();
  const std::string path = dir.empty() ? std::string(name) : dir + "/lib" + name + ".so";
  return std::string("<Library path=\"") + path + "\" initFunction=\"" + init + "\" finalizeFunction=\"" +
         finalize + "\"/>";
}

std::string security_config(const SecurityFiles& files) {
  std::string xml = "<Security><Authentication>";
  xml += plugin_library("dds_security_auth", "init_authentication", "finalize_authentication");
  xml += "<IdentityCA>file:" + files.identity_ca + "</IdentityCA>";
  xml += "<IdentityCertificate>file:" + files.identity_certificate + "</IdentityCertificate>";
  xml += "<PrivateKey>file:" + files.identity_private_key + "</PrivateKey>";
  xml += "</Authentication><AccessControl>";
  xml += plugin_library("dds_security_ac", "init_access_control", "finalize_access_control");
  xml += "<PermissionsCA>file:" + files.permissions_ca + "</PermissionsCA>";
  xml += "<Governance>file:" + files.governance + "</Governance>";
  xml += "<Permissions>file:" + files.permissions + "</Permissions>";
  xml += "</AccessControl><Cryptographic>";
  xml += plugin_library("dds_security_crypto", "init_crypto", "finalize_crypto");
  xml += "</Cryptographic></Security>";
  return xml;
}

}  // namespace

std::string security_plugin_dir() { return HAPTIC_DDS_SECURITY_PLUGIN_DIR; }

bool security_plugins_available() {
  const std::string dir = security_plugin_dir();
  if (dir.empty()) return false;
  for (const char* name : {"auth", "ac", "crypto"}) {
    if (!readable_file(dir + "/libdds_security_" + name + ".so")) return false;
  }
  return true;
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
    xml += "</Peers>";
  }
  if (options.local_domain_id) {
    xml += options.peers.empty() ? "<Discovery>" : "";
    xml += "<ExternalDomainId>" + std::to_string(options.domain_id) + "</ExternalDomainId>";
  }
  if (!options.peers.empty() || options.local_domain_id) xml += "</Discovery>";
  if (options.security) xml += security_config(*options.security);
  xml += "</Domain></CycloneDDS>";
  return xml;
}

std::string dds_error(dds_return_t code) { return dds_strretcode(code); }

Participant::Participant(const DomainOptions& options) : options_(options) {
  if (std::string error = validate(options); !error.empty()) throw std::runtime_error("federation." + error);
  const std::string config = cyclone_config(options);
  const dds_domainid_t local = options.local_domain_id.value_or(options.domain_id);
  // A domain another participant of this process already made is reused as it is configured.
  const dds_entity_t domain = dds_create_domain(local, config.c_str());
  if (domain > 0) {
    domain_ = domain;
  } else if (domain != DDS_RETCODE_PRECONDITION_NOT_MET) {
    throw std::runtime_error("DDS domain " + std::to_string(options.domain_id) + ": " + dds_error(domain) +
                             " (interface \"" + options.interface + "\")");
  }
  participant_ = dds_create_participant(local, nullptr, nullptr);
  if (participant_ < 0) {
    std::string reason = dds_error(participant_);
    if (options.security) {
      // Cyclone's log (stderr) names the check that failed; these are the usual ones.
      reason += " (DDS Security refused this site's files: the identity must be signed by identity_ca "
                "and its key must match it, governance and permissions signed by permissions_ca, the "
                "permissions must name the identity's subject and this domain, and all must be valid now)";
    }
    if (domain_ > 0) dds_delete(domain_);
    throw std::runtime_error("DDS participant in domain " + std::to_string(options.domain_id) + ": " + reason);
  }
}

Participant::~Participant() {
  if (participant_ > 0) dds_delete(participant_);
  if (domain_ > 0) dds_delete(domain_);
}

}  // namespace haptic::federation
