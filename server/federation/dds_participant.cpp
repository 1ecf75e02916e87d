#include "federation/dds_participant.hpp"

#include <filesystem>
#include <fstream>
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

/// An absolute file path of letters, digits and / . _ - + only: it goes into the XML as a file:
/// URI, so nothing in it may end the element or be read as markup.
bool plain_path(const std::string& path) {
  if (path.size() < 2 || path.size() > 1024 || path.front() != '/') return false;
  for (const char c : path) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '/' || c == '.' || c == '_' || c == '-' || c == '+';
    if (!ok) return false;
  }
  return true;
}

/// A regular file this process can open for reading.
bool readable_file(const std::string& path) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) return false;
  return std::ifstream(path).good();
}

/// Each security file with its option's name, in the order they are checked.
std::vector<std::pair<const char*, const std::string*>> security_fields(const SecurityFiles& files) {
  return {{"identity_ca", &files.identity_ca},
          {"identity_certificate", &files.identity_certificate},
          {"identity_private_key", &files.identity_private_key},
          {"permissions_ca", &files.permissions_ca},
          {"governance", &files.governance},
          {"permissions", &files.permissions}};
}

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
  if (options.local_domain_id && *options.local_domain_id == DDS_DOMAIN_DEFAULT) {
    return "local_domain_id: must not be DDS_DOMAIN_DEFAULT";
  }
  if (options.security) {
    // Governance and permissions documents name domains 0 to 230 (Cyclone's parser refuses more).
    if (options.domain_id > 230) {
      return "domain_id: must be 0 to 230 with security (the DDS Security documents name no higher), got " +
             std::to_string(options.domain_id);
    }
    for (const auto& [name, path] : security_fields(*options.security)) {
      const std::string field = std::string("security.") + name;
      if (path->empty()) return field + ": required with security (a file's absolute path)";
      if (!plain_path(*path)) {
        return field + ": must be an absolute path of letters, digits and / . _ - +, got \"" + *path + "\"";
      }
      if (!readable_file(*path)) return field + ": cannot read " + *path;
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
