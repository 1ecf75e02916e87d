#include "config/federation_options.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>

#include "haptic/io/loopback.hpp"

namespace haptic::config {

namespace {

federation::DomainOptions domain_of(const v1::FederationConfig& federation) {
  federation::DomainOptions domain;
  domain.domain_id = federation.domain_id();
  domain.interface = federation.interface();
  domain.peers.assign(federation.peers().begin(), federation.peers().end());
  if (federation.has_security()) {
    const v1::FederationSecurityConfig& security = federation.security();
    domain.security = federation::SecurityFiles{security.identity_ca(),    security.identity_certificate(),
                                                security.identity_private_key(), security.permissions_ca(),
                                                security.governance(),     security.permissions()};
  }
  return domain;
}

federation::Ros2Options ros2_of(const v1::Ros2Config& ros2) {
  federation::Ros2Options out;
  out.ros_namespace = ros2.ros_namespace();
  out.frame_id = ros2.frame_id();
  if (ros2.has_wrench_input()) out.wrench_topic = ros2.wrench_input().topic();
  out.stamp_clock = ros2.stamp_clock() == v1::Ros2Config::SERVER_TIME
                        ? federation::Ros2Options::StampClock::kServerTime
                        : federation::Ros2Options::StampClock::kSystemTime;
  return out;
}

/// A loopback interface (by name or by a numeric loopback address): the federation stays on this
/// host.
bool loopback(const std::string& interface) { return interface == "lo" || io::is_loopback_literal(interface); }

}  // namespace

void fill_federation_defaults(v1::FederationConfig& federation) {
  if (federation.interface().empty()) federation.set_interface("lo");
  const runtime::AvatarParams avatar;
  v1::AvatarConfig& avatar_config = *federation.mutable_avatar();
  if (!avatar_config.has_radius()) avatar_config.set_radius(avatar.radius);
  if (!avatar_config.has_stiffness()) avatar_config.set_stiffness(avatar.stiffness);
  if (!avatar_config.has_damping()) avatar_config.set_damping(avatar.damping);
  const runtime::MassCouplingParams coupling;
  const federation::CreditCap credit;
  v1::PeerCreditConfig& peer_credit = *federation.mutable_peer_credit();
  if (!peer_credit.has_max_power_w()) peer_credit.set_max_power_w(credit.max_power_W);
  if (!peer_credit.has_burst_j()) peer_credit.set_burst_j(credit.burst_J);
  v1::SharedMassConfig& masses = *federation.mutable_shared_masses();
  if (!masses.has_coupling_stiffness()) masses.set_coupling_stiffness(coupling.stiffness);
  if (!masses.has_coupling_damping()) masses.set_coupling_damping(coupling.damping);
  if (!federation.has_ros2()) return;
  v1::Ros2Config& ros2 = *federation.mutable_ros2();
  if (ros2.ros_namespace().empty()) {
    std::string name = federation.site();
    for (char& c : name) {
      if (c == '-' || c == '.') c = '_';
    }
    ros2.set_ros_namespace("/hapticd/" + name);
  }
  if (ros2.rate_hz() == 0.0) ros2.set_rate_hz(100.0);
  if (ros2.frame_id().empty()) ros2.set_frame_id("hapticd_world");
  if (ros2.has_wrench_input()) {
    v1::Ros2WrenchInputConfig& input = *ros2.mutable_wrench_input();
    const runtime::RobotWrenchParams defaults;
    if (input.topic().empty()) input.set_topic("wrench_command");
    if (!input.has_force_scale()) input.set_force_scale(defaults.force_scale);
    if (!input.has_stale_s()) input.set_stale_s(defaults.stale_s);
  }
}

std::string validate_federation(const v1::FederationConfig& federation, double loop_rate_hz) {
  const std::string& site = federation.site();
  if (site.empty() || site.size() > 64) {
    return "federation.site: must be 1 to 64 characters (this site's name in the domain), got " +
           std::to_string(site.size());
  }
  // The name is the site's DDS partition, where '*', '?' and '[' would be patterns speaking for
  // other sites, and its certificate's subject (scripts/federation-certs allows the same).
  const auto plain = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '.' || c == '_' || c == '-'; };
  if (!std::isalnum(static_cast<unsigned char>(site[0])) || !std::all_of(site.begin(), site.end(), plain)) {
    return "federation.site: letters, digits, '.', '_' and '-' only, starting with a letter or digit (it is the "
           "site's DDS partition and certificate subject), got \"" + site + "\"";
  }
  if (std::string e = federation::validate(domain_of(federation)); !e.empty()) return "federation." + e;
  if (!loopback(federation.interface()) && !federation.has_security() && !federation.allow_insecure()) {
    return "federation.interface: \"" + federation.interface() +
           "\" leaves this host without DDS Security: anyone on that network could read the tools and "
           "join the domain; set federation.security (scripts/federation-certs makes its files), use "
           "\"lo\", or accept that with federation.allow_insecure: true";
  }
  const auto in_range = [](const char* field, double value, double low, double high, bool low_open) {
    const bool ok = std::isfinite(value) && (low_open ? value > low : value >= low) && value <= high;
    if (ok) return std::string();
    std::ostringstream out;
    out << "federation." << field << ": must be " << (low_open ? "> " : "") << low << (low_open ? " and at most " : " to ")
        << high << ", got " << value;
    return out.str();
  };
  for (const std::string& e : {in_range("avatar.radius", federation.avatar().radius(), 0.0, 0.5, true),
                               in_range("avatar.stiffness", federation.avatar().stiffness(), 0.0, 1e5, false),
                               in_range("avatar.damping", federation.avatar().damping(), 0.0, 1e3, false),
                               in_range("shared_masses.coupling_stiffness", federation.shared_masses().coupling_stiffness(), 0.0, 1e5, false),
                               in_range("shared_masses.coupling_damping", federation.shared_masses().coupling_damping(), 0.0, 1e3, false),
                               in_range("peer_credit.max_power_w", federation.peer_credit().max_power_w(), 0.0, 1e3, true),
                               in_range("peer_credit.burst_j", federation.peer_credit().burst_j(), 0.0, 100.0, true)}) {
    if (!e.empty()) return e;
  }
  if (federation.has_ros2()) {
    const v1::Ros2Config& ros2 = federation.ros2();
    if (std::string e = federation::validate(ros2_of(ros2)); !e.empty()) {
      const std::string topic = "wrench_topic";  // the relay's name for wrench_input.topic
      if (e.rfind(topic, 0) == 0) e = "wrench_input.topic" + e.substr(topic.size());
      return "federation.ros2." + e;
    }
    const double rate = ros2.rate_hz();
    if (!std::isfinite(rate) || rate < 1.0 || rate > 1000.0 || rate > loop_rate_hz) {
      return "federation.ros2.rate_hz: must be 1 to 1000 and at most the loop rate (" +
             std::to_string(loop_rate_hz) + " Hz), got " + std::to_string(rate);
    }
    if (ros2.has_wrench_input()) {
      const v1::Ros2WrenchInputConfig& input = ros2.wrench_input();
      for (const std::string& e : {in_range("ros2.wrench_input.force_scale", input.force_scale(), 0.0, 10.0, false),
                                   in_range("ros2.wrench_input.stale_s", input.stale_s(), 0.01, 5.0, false)}) {
        if (!e.empty()) return e;
      }
    }
  }
  return {};
}

std::vector<std::string> federation_warnings(const v1::FederationConfig& federation) {
  std::vector<std::string> warnings;
  const bool on_loopback = loopback(federation.interface());
  if (!on_loopback && !federation.has_security() && federation.allow_insecure()) {
    warnings.push_back("federation: interface \"" + federation.interface() +
                       "\" without DDS Security (allow_insecure): anyone on that network can read the tools and "
                       "join the domain; federation.security (scripts/federation-certs) closes it");
  }
  if (on_loopback) {
    for (const std::string& peer : federation.peers()) {
      if (!io::is_loopback_literal(peer)) {
        warnings.push_back("federation: peer \"" + peer + "\" is not on this host, but the interface is \"" +
                           federation.interface() + "\": it is never reached; set federation.interface to the "
                           "interface (or address) on that peer's network");
      }
    }
  }
  return warnings;
}

federation::RelayOptions relay_options(const v1::FederationConfig& federation, double loop_rate_hz) {
  federation::RelayOptions options;
  options.site = federation.site();
  options.domain = domain_of(federation);
  options.rate_hz = loop_rate_hz;  // every site's tools at loop rate
  options.credit = federation::CreditCap{federation.peer_credit().max_power_w(), federation.peer_credit().burst_j()};
  if (federation.has_ros2()) {
    options.ros2 = ros2_of(federation.ros2());
    options.ros2_every = static_cast<std::uint32_t>(std::max(1.0, std::round(loop_rate_hz / federation.ros2().rate_hz())));
  }
  return options;
}

}  // namespace haptic::config

namespace haptic::config {

runtime::AvatarParams avatar_params(const v1::FederationConfig& federation) {
  const v1::AvatarConfig& avatar = federation.avatar();
  return runtime::AvatarParams{avatar.radius(), avatar.stiffness(), avatar.damping()};
}

runtime::MassCouplingParams mass_coupling(const v1::FederationConfig& federation) {
  const v1::SharedMassConfig& masses = federation.shared_masses();
  return runtime::MassCouplingParams{masses.coupling_stiffness(), masses.coupling_damping()};
}

}  // namespace haptic::config

namespace haptic::config {

runtime::RobotWrenchParams robot_wrench_params(const v1::FederationConfig& federation) {
  const v1::Ros2WrenchInputConfig& input = federation.ros2().wrench_input();
  return runtime::RobotWrenchParams{input.force_scale(), input.stale_s()};
}

}  // namespace haptic::config
