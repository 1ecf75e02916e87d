#include "federation/options.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace haptic::federation {

namespace {

bool name_char(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_'; }

}  // namespace

bool plain_name(const std::string& text) {
  if (text.empty() || text.size() > 253) return false;
  for (const char c : text) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '.' || c == ':' || c == '-' || c == '_';
    if (!ok) return false;
  }
  return true;
}

bool plain_path(const std::string& path) {
  if (path.size() < 2 || path.size() > 1024 || path.front() != '/') return false;
  for (const char c : path) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '/' || c == '.' || c == '_' || c == '-' || c == '+';
    if (!ok) return false;
  }
  return true;
}

bool readable_file(const std::string& path) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) return false;
  return std::ifstream(path).good();
}

std::vector<std::pair<const char*, const std::string*>> security_fields(const SecurityFiles& files) {
  return {{"identity_ca", &files.identity_ca},
          {"identity_certificate", &files.identity_certificate},
          {"identity_private_key", &files.identity_private_key},
          {"permissions_ca", &files.permissions_ca},
          {"governance", &files.governance},
          {"permissions", &files.permissions}};
}

std::string validate(const DomainOptions& options) {
  // DDSI's default port mapping (PB 7400, DG 250) leaves room for domains 0 ... 232.
  if (options.domain_id > 232) {
    return "domain_id: must be 0 to 232, got " + std::to_string(options.domain_id);
  }
  if (!plain_name(options.interface)) {
    return "interface: must be an interface name or address (letters, digits, . : - _), got \"" +
           options.interface + "\"";
  }
  for (std::size_t i = 0; i < options.peers.size(); ++i) {
    if (!plain_name(options.peers[i])) {
      return "peers[" + std::to_string(i) + "]: must be a host name or address, got \"" + options.peers[i] + "\"";
    }
  }
  if (options.local_domain_id && *options.local_domain_id == kDdsDomainDefault) {
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

std::string validate(const Ros2Options& options) {
  const std::string& ns = options.ros_namespace;
  bool ok = ns.size() >= 2 && ns.size() <= 200 && ns.front() == '/' && ns.back() != '/';
  for (std::size_t i = 1; ok && i < ns.size(); ++i) {
    ok = name_char(ns[i]) || (ns[i] == '/' && ns[i - 1] != '/');
  }
  if (!ok) {
    return "ros_namespace: must be '/' and names of letters, digits and '_' separated by '/', got \"" + ns + "\"";
  }
  if (options.frame_id.empty() || options.frame_id.size() > 200) {
    return "frame_id: must be 1 to 200 characters, got " + std::to_string(options.frame_id.size());
  }
  if (options.buttons > 32) return "buttons: at most 32, got " + std::to_string(options.buttons);
  if (!options.wrench_topic.empty()) {
    const std::string& topic = options.wrench_topic;
    bool relative = topic.size() <= 200 && topic.front() != '/' && topic.back() != '/';
    for (std::size_t i = 0; relative && i < topic.size(); ++i) {
      relative = name_char(topic[i]) || (topic[i] == '/' && topic[i - 1] != '/');
    }
    if (!relative) {
      return "wrench_topic: must be names of letters, digits and '_' separated by '/' (under the namespace), got \"" +
             topic + "\"";
    }
    for (const char* published : kRos2PublishedTopics) {
      if ("/" + topic == published) {
        return "wrench_topic: \"" + topic + "\" is one hapticd publishes";
      }
    }
  }
  return {};
}

std::string validate(const CreditCap& cap) {
  const auto check = [](const char* field, double value, double high) {
    if (std::isfinite(value) && value > 0.0 && value <= high) return std::string();
    std::ostringstream out;
    out << field << ": must be > 0 and at most " << high << ", got " << value;
    return out.str();
  };
  if (std::string e = check("max_power_W", cap.max_power_W, 1000.0); !e.empty()) return e;
  return check("burst_J", cap.burst_J, 100.0);
}

}  // namespace haptic::federation
