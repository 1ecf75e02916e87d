#pragma once
// The federation's options, free of DDS: what a site's configuration says (its domain, its DDS
// Security files, its ROS 2 topics, what a peer may be credited, the relay's rates) and the checks
// that name a bad field. haptic::config builds them from hapticd's configuration and links this
// alone (haptic::federation_options), so that neither it nor haptic-lab links Cyclone DDS; the
// federation (haptic::federation) takes them.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace haptic::federation {

/// DDS Security (OMG DDS Security 1.1, Cyclone's builtin plugins): a site's files, each an absolute
/// path. scripts/federation-certs makes them; docs/federation.md, "Security", says what they do.
struct SecurityFiles {
  std::string identity_ca;           // PEM: the CA that signed every site's identity
  std::string identity_certificate;  // PEM: this site's identity, signed by identity_ca
  std::string identity_private_key;  // PEM, unencrypted: the identity's key
  std::string permissions_ca;        // PEM: the CA that signed the governance and permissions
  std::string governance;            // S/MIME: the domain's rules, the same at every site
  std::string permissions;           // S/MIME: what this site may publish and subscribe
};

struct DomainOptions {
  std::uint32_t domain_id = 0;  // DDS domain, 0 ... 232 (the RTPS port mapping's range); with security 0 ... 230.
  /// The one network interface the domain uses, by name ("lo", "eth0") or address.
  std::string interface = "lo";
  /// Unicast discovery: the addresses of the other sites' hosts. Empty: multicast discovery.
  std::vector<std::string> peers;
  /// Set: authenticated, access-controlled and encrypted (the governance document says how much);
  /// only sites with an identity from identity_ca take part.
  std::optional<SecurityFiles> security;
  /// Cyclone's domain inside this process when it is not domain_id (which is then the domain on
  /// the network): each such domain has a configuration of its own, so several sites with
  /// different identities can share one process, as tests need. Unset: domain_id.
  std::optional<std::uint32_t> local_domain_id;
};

/// "" or one message naming the bad option ("domain_id: must be 0 to 232, got 300",
/// "security.governance: cannot read /x/gov.p7s").
std::string validate(const DomainOptions& options);

struct Ros2Options {
  /// The ROS namespace of the topics, "/hapticd/<site>/port0" say: a leading '/', then names of
  /// letters, digits and '_' separated by '/'.
  std::string ros_namespace = "/hapticd";
  std::string frame_id = "hapticd_world";  // header.frame_id: the device's W
  std::uint32_t buttons = 0;               // how many buttons Joy reports
  /// The topic a ROS 2 node sends the tool's force on, under ros_namespace ("wrench_command":
  /// <namespace>/wrench_command): a relative ROS name, not one of the four published. "": none.
  std::string wrench_topic;
  /// What header.stamp counts: the host's wall clock at publication (what ROS tools compare), or
  /// the tick's server time (reproducible in lockstep).
  enum class StampClock { kSystemTime, kServerTime };
  StampClock stamp_clock = StampClock::kSystemTime;
};

/// "" or one message naming the bad option.
std::string validate(const Ros2Options& options);

/// The ROS topics a tool is published on, under its namespace (ros2_topics.hpp), in this order.
inline constexpr const char* kRos2PublishedTopics[] = {"/pose", "/twist", "/wrench", "/joy"};


/// The most energy a peer is credited per coupling. Give every site the same.
struct CreditCap {
  /// Sustained. Unit: W. > 0. Honest peers in the lockstep runs of whole sites (hands pushing each
  /// other's tools and a shared mass, 0 to 100 ms one way, 20 % loss) never send more than 0.2 W
  /// over 0.02 J (a cap of 0.05 W, 5 mJ refuses them 0.3 mJ at most).
  double max_power_W = 1.0;
  double burst_J = 0.1;      // at once: the bucket's size, and how far claims may run over it. Unit: J. > 0.
};

/// "" or one message naming the bad field ("max_power_W: must be > 0 and at most 1000, got -1").
std::string validate(const CreditCap& cap);

struct RelayOptions {
  std::string site;                 // this site's name (1 ... 64 characters)
  DomainOptions domain;
  std::optional<Ros2Options> ros2;  // ros2.ros_namespace is the site's; ports add "/port<N>"
  double rate_hz = 1000.0;          // the relay's periods per second (the loop's rate). Unit: Hz.
  std::uint32_t ros2_every = 10;    // ROS 2 topics every this many periods (≥ 1)
  bool tools = true;                // the tool topic: publish this site's tools, render the others'
  /// A remote tool or mass copy not heard from for this long is dropped from the mailboxes (its
  /// site stopped or left the network): its avatar and its coupling go. Unit: s.
  double silence_s = 0.5;
  /// Where the relay says what it refused (a ROS 2 wrench's frame, ...) and which sites come and
  /// go; unset: nowhere.
  std::function<void(const std::string&)> log;
  /// A site's arrivals, and its departures, logged at most once in this long each (further ones
  /// counted, then summarized). Unit: s.
  double log_window_s = 10.0;
  /// The most energy another site is credited per coupling (tools' and mass copies').
  CreditCap credit;
};

/// DDS_DOMAIN_DEFAULT (dds/dds.h), which local_domain_id must not be; dds_participant.cpp checks
/// that they agree.
inline constexpr std::uint32_t kDdsDomainDefault = 0xffffffffu;

/// What may go into Cyclone's configuration XML as a name or address: letters, digits and
/// . : - _ only (an interface name, a host name, an IPv4 or IPv6 address), so that no option can
/// inject configuration.
bool plain_name(const std::string& text);
/// An absolute file path of letters, digits and / . _ - + only: it goes into the XML as a file:
/// URI, so nothing in it may end the element or be read as markup.
bool plain_path(const std::string& path);
/// A regular file this process can open for reading.
bool readable_file(const std::string& path);
/// Each security file with its option's name, in the order they are checked.
std::vector<std::pair<const char*, const std::string*>> security_fields(const SecurityFiles& files);

}  // namespace haptic::federation
