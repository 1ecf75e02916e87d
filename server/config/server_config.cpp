#include "config/server_config.hpp"

#include <arpa/inet.h>
#include <google/protobuf/util/json_util.h>
#include <netdb.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <cstring>
#include <fstream>
#include <sstream>
#include <tuple>
#include <thread>

#include "config/devices.hpp"
#include "config/federation_options.hpp"
#include "config/security.hpp"
#include "haptic/io/bounded_file.hpp"
#include "haptic/io/loopback.hpp"
#include "haptic/io/scene_file.hpp"
#include "schema/scene_specs.hpp"

namespace haptic::config {
namespace {

/// Refuses a non-loopback bind address unless the control plane has TLS and tokens, or remote
/// access without them was accepted.
std::string check_exposure(const v1::ServerConfig& config) {
  if (config.insecure_remote_access() || secured_for_remote_access(config.security())) return {};
  const auto refuse = [&config](const char* field, const std::string& address) {
    const v1::SecurityConfig& security = config.security();
    const bool tokens = security.tokens_size() > 0 || !security.tokens_file().empty();
    const std::string missing = !security.has_tls() && !tokens ? "neither TLS nor tokens"
                                : !security.has_tls()          ? "tokens but no TLS"
                                                               : "TLS but no tokens";
    return std::string(field) + ": '" + address + "' is not a loopback address, and security has " +
           missing + ", so anyone who reaches it could open a session and command forces on the "
           "device. Configure security.tls and security.tokens (docs/deployment.md), bind "
           "127.0.0.1 (the default), or accept the risk with --insecure (insecure_remote_access: true)";
  };
  if (!is_loopback_host(host_of_address(config.grpc_address()))) {
    return refuse("grpc_address", config.grpc_address());
  }
  if (!is_loopback_host(config.udp_address())) return refuse("udp_address", config.udp_address());
  // The HTTP face carries the same calls, with the control plane's TLS when there is one.
  if (!config.http_address().empty() && !is_loopback_host(host_of_address(config.http_address()))) {
    return refuse("http_address", config.http_address());
  }
  return {};
}

/// An HTTP endpoint's address: empty (none), HOST:PORT or [IPv6]:PORT.
std::string check_http_address(const char* field, const std::string& address) {
  if (address.empty()) return {};
  const auto colon = address.rfind(':');
  const std::string port = colon == std::string::npos ? std::string() : address.substr(colon + 1);
  const bool digits = !port.empty() && port.size() <= 5 &&
                      port.find_first_not_of("0123456789") == std::string::npos;
  const std::string host = host_of_address(address);
  const bool bare_ipv6 = host.find(':') != std::string::npos && address.front() != '[';
  if (!digits || std::stoi(port) > 65535 || host.empty() || bare_ipv6) {
    return std::string(field) + ": must be HOST:PORT or [IPv6]:PORT (port 0 to 65535; 0 picks one), got '" +
           address + "'";
  }
  return {};
}

/// The viewer speaks plain HTTP: a bearer token typed into its page would cross the network in
/// clear, so with tokens a non-loopback viewer_address needs insecure_remote_access.
std::string check_viewer_exposure(const v1::ServerConfig& config) {
  const v1::SecurityConfig& security = config.security();
  const bool tokens = security.tokens_size() > 0 || !security.tokens_file().empty();
  if (config.viewer_address().empty() || !tokens || config.insecure_remote_access() ||
      is_loopback_host(host_of_address(config.viewer_address()))) {
    return {};
  }
  return "viewer_address: '" + config.viewer_address() +
         "' is not a loopback address, and the viewer speaks plain HTTP, so the bearer tokens its "
         "page sends would cross the network in clear. Bind 127.0.0.1 (the default of --http PORT) "
         "and reach it through an SSH tunnel (docs/viewer.md), or accept the risk with --insecure "
         "(insecure_remote_access: true)";
}

/// An origin as a browser sends it: scheme://host[:port], http or https, nothing after.
std::string check_origin(const std::string& origin) {
  const auto scheme_end = origin.find("://");
  if (scheme_end == std::string::npos) return "has no scheme";
  const std::string scheme = origin.substr(0, scheme_end);
  if (scheme != "http" && scheme != "https") return "its scheme is not http or https";
  std::string rest = origin.substr(scheme_end + 3);
  std::string host;
  if (!rest.empty() && rest.front() == '[') {
    const auto close = rest.find(']');
    if (close == std::string::npos) return "its IPv6 address has no ']'";
    host = rest.substr(1, close - 1);
    rest = rest.substr(close + 1);
    if (host.empty() || host.find_first_not_of("0123456789abcdefABCDEF:.") != std::string::npos) {
      return "its IPv6 address is not one";
    }
  } else {
    const auto colon = rest.find(':');
    host = rest.substr(0, colon);
    rest = colon == std::string::npos ? "" : rest.substr(colon);
    if (host.empty() || host.find_first_not_of("abcdefghijklmnopqrstuvwxyz"
                                               "ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789.-") != std::string::npos) {
      return "its host is not a name or an address (nothing may follow it but :PORT)";
    }
  }
  if (rest.empty()) return {};
  const std::string port = rest.substr(1);
  if (rest.front() != ':' || port.empty() || port.size() > 5 ||
      port.find_first_not_of("0123456789") != std::string::npos || std::stoi(port) > 65535) {
    return "nothing may follow its host but :PORT (1 to 65535)";
  }
  return {};
}

std::string check_origins(const v1::ServerConfig& config) {
  for (int i = 0; i < config.http_allowed_origins_size(); ++i) {
    const std::string& origin = config.http_allowed_origins(i);
    if (const std::string why = check_origin(origin); !why.empty()) {
      return "http_allowed_origins[" + std::to_string(i) + "]: '" + origin.substr(0, 200) + "' " + why +
             "; an origin is http://HOST[:PORT] or https://HOST[:PORT], as a browser sends it";
    }
  }
  return {};
}

}  // namespace

std::string host_of_address(const std::string& address) {
  if (!address.empty() && address.front() == '[') {
    const auto end = address.find(']');
    return end == std::string::npos ? address : address.substr(1, end - 1);
  }
  const auto colon = address.rfind(':');
  // "::1" alone (no port) has more than one colon: all of it is the host.
  if (colon == std::string::npos || address.find(':') != colon) return address;
  return address.substr(0, colon);
}

bool is_loopback_host(const std::string& host) {
  if (host.empty()) return false;  // every interface
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  if (::getaddrinfo(host.c_str(), nullptr, &hints, &found) != 0 || found == nullptr) return false;
  bool all_loopback = true;
  for (const addrinfo* ai = found; ai != nullptr; ai = ai->ai_next) {
    all_loopback = all_loopback && io::is_loopback_address(ai->ai_addr);
  }
  ::freeaddrinfo(found);
  return all_loopback;
}

std::uint32_t default_spin_us(double rate_hz) {
  const double period_us = 1e6 / rate_hz;
  return static_cast<std::uint32_t>(std::min(200.0, std::floor(0.8 * period_us)));
}

void fill_defaults(v1::ServerConfig& config) {
  if (config.grpc_address().empty()) config.set_grpc_address("127.0.0.1:50051");
  if (config.has_federation()) fill_federation_defaults(*config.mutable_federation());
  if (config.udp_address().empty()) config.set_udp_address("127.0.0.1");
  if (!config.has_udp_port()) config.set_udp_port(50052);
  if (!config.has_loop_rate_hz()) config.set_loop_rate_hz(1000.0);
  if (config.time_mode() == v1::TIME_MODE_UNSPECIFIED) config.set_time_mode(v1::REAL_TIME);
  if (config.lease_timeout_ms() == 0) config.set_lease_timeout_ms(1000);
  if (config.removal_ramp_ms() == 0) config.set_removal_ramp_ms(50);
  if (!config.has_status_period_s()) config.set_status_period_s(5);
  if (config.max_sessions() == 0) config.set_max_sessions(32);
  if (config.max_objects_per_session() == 0) config.set_max_objects_per_session(256);
  if (config.max_event_streams() == 0) config.set_max_event_streams(32);
  if (config.max_event_streams_per_session() == 0) config.set_max_event_streams_per_session(4);
  if (config.max_sessions_per_peer() == 0) {
    config.set_max_sessions_per_peer(std::min<std::uint32_t>(16, config.max_sessions()));
  }
  if (config.session_open_rate_per_peer() == 0.0) config.set_session_open_rate_per_peer(10.0);
  if (config.session_open_burst_per_peer() == 0) config.set_session_open_burst_per_peer(32);
  if (config.handshake_timeout_ms() == 0) config.set_handshake_timeout_ms(5000);
  if (config.max_scene_triangles() == 0) config.set_max_scene_triangles(200'000);
  if (config.max_scene_bytes() == 0) config.set_max_scene_bytes(64ull << 20);
  // The shares: half the whole of each, rounded up.
  const auto half = [](std::uint64_t whole) { return (whole + 1) / 2; };
  if (config.max_scene_triangles_per_session() == 0) {
    config.set_max_scene_triangles_per_session(static_cast<std::uint32_t>(half(config.max_scene_triangles())));
  }
  if (config.max_scene_triangles_per_peer() == 0) {
    config.set_max_scene_triangles_per_peer(static_cast<std::uint32_t>(half(config.max_scene_triangles())));
  }
  if (config.max_scene_bytes_per_session() == 0) config.set_max_scene_bytes_per_session(half(config.max_scene_bytes()));
  if (config.max_scene_bytes_per_peer() == 0) config.set_max_scene_bytes_per_peer(half(config.max_scene_bytes()));
  if (config.max_event_streams_per_peer() == 0) {
    config.set_max_event_streams_per_peer(static_cast<std::uint32_t>(half(config.max_event_streams())));
  }
  if (config.max_sessions_per_token() == 0) config.set_max_sessions_per_token(config.max_sessions_per_peer());
  if (config.max_event_streams_per_token() == 0) {
    config.set_max_event_streams_per_token(config.max_event_streams_per_peer());
  }

  fill_point_mass_defaults(*config.mutable_simulated_point_mass());
  for (v1::DeviceConfig& extra : *config.mutable_extra_devices()) {
    if (extra.has_simulated_point_mass()) fill_point_mass_defaults(*extra.mutable_simulated_point_mass());
  }

  auto* real_time = config.mutable_real_time();
  if (!real_time->has_use_fifo()) real_time->set_use_fifo(true);
  if (real_time->fifo_priority() == 0) real_time->set_fifo_priority(80);
  if (real_time->spin_us() == 0 && config.loop_rate_hz() > 0.0) {
    real_time->set_spin_us(default_spin_us(config.loop_rate_hz()));
  }
  // real_time.cpu left unset: the server picks a CPU no other hapticd's loop holds when it starts
  // (runtime/loop_cpu.hpp).
  if (!real_time->has_sender_cpu()) real_time->set_sender_cpu(kSenderOnLoopCpu);
  if (!real_time->has_sender_priority()) {
    real_time->set_sender_priority(real_time->use_fifo() ? real_time->fifo_priority() - 1 : 0);
  }

  if (config.initial_operator().mode() == v1::OperatorInput::MODE_UNSPECIFIED) {
    config.mutable_initial_operator()->set_mode(v1::OperatorInput::NONE);
  }
}

v1::ServerConfig default_config() {
  v1::ServerConfig config;
  fill_defaults(config);
  return config;
}

std::string validate(const v1::ServerConfig& config) {
  if (config.loop_rate_hz() < 100.0 || config.loop_rate_hz() > 10000.0 ||
      !std::isfinite(config.loop_rate_hz())) {
    return "loop_rate_hz: must be in [100, 10000], got " + std::to_string(config.loop_rate_hz());
  }
  if (config.udp_port() > 65535) {
    return "udp_port: must be 0 to 65535, got " + std::to_string(config.udp_port());
  }
  if (const std::string& dir = config.recording_dir();
      !dir.empty() && !std::filesystem::is_directory(dir)) {
    return "recording_dir: '" + dir + "' is not a folder (StartRecording writes its files there)";
  }
  if (auto e = check_http_address("metrics_address", config.metrics_address()); !e.empty()) return e;
  if (auto e = check_http_address("viewer_address", config.viewer_address()); !e.empty()) return e;
  if (auto e = check_viewer_exposure(config); !e.empty()) return e;
  if (auto e = check_http_address("http_address", config.http_address()); !e.empty()) return e;
  if (auto e = check_origins(config); !e.empty()) return e;
  if (config.time_mode() != v1::REAL_TIME && config.time_mode() != v1::LOCKSTEP) {
    return "time_mode: must be REAL_TIME or LOCKSTEP";
  }
  if (auto e = validate_security(config.security()); !e.empty()) return e;
  if (config.has_federation()) {
    if (auto e = validate_federation(config.federation(), config.loop_rate_hz()); !e.empty()) return e;
  }
  if (auto e = check_exposure(config); !e.empty()) return e;
  if (config.max_sessions_per_peer() > config.max_sessions()) {
    return "max_sessions_per_peer: must be at most max_sessions (" +
           std::to_string(config.max_sessions()) + "), got " +
           std::to_string(config.max_sessions_per_peer());
  }
  if (!(std::isfinite(config.session_open_rate_per_peer()) && config.session_open_rate_per_peer() > 0.0 &&
        config.session_open_rate_per_peer() <= 1000.0)) {
    return "session_open_rate_per_peer: must be in (0, 1000] a second, got " +
           std::to_string(config.session_open_rate_per_peer());
  }
  if (config.session_open_burst_per_peer() > 100'000) {
    return "session_open_burst_per_peer: must be 1 to 100000, got " +
           std::to_string(config.session_open_burst_per_peer());
  }
  if (config.handshake_timeout_ms() < 100 || config.handshake_timeout_ms() > 60'000) {
    return "handshake_timeout_ms: must be 100 to 60000, got " +
           std::to_string(config.handshake_timeout_ms());
  }
  if (config.max_event_streams() > 1024) {
    return "max_event_streams: must be 1 to 1024 (each holds a thread), got " +
           std::to_string(config.max_event_streams());
  }
  for (const auto& [share, share_value, whole, whole_value] :
       {std::tuple{"max_scene_triangles_per_session", std::uint64_t{config.max_scene_triangles_per_session()},
                   "max_scene_triangles", std::uint64_t{config.max_scene_triangles()}},
        std::tuple{"max_scene_triangles_per_peer", std::uint64_t{config.max_scene_triangles_per_peer()},
                   "max_scene_triangles", std::uint64_t{config.max_scene_triangles()}},
        std::tuple{"max_scene_bytes_per_session", config.max_scene_bytes_per_session(), "max_scene_bytes",
                   config.max_scene_bytes()},
        std::tuple{"max_scene_bytes_per_peer", config.max_scene_bytes_per_peer(), "max_scene_bytes",
                   config.max_scene_bytes()},
        std::tuple{"max_event_streams_per_peer", std::uint64_t{config.max_event_streams_per_peer()},
                   "max_event_streams", std::uint64_t{config.max_event_streams()}},
        std::tuple{"max_event_streams_per_token", std::uint64_t{config.max_event_streams_per_token()},
                   "max_event_streams", std::uint64_t{config.max_event_streams()}},
        std::tuple{"max_sessions_per_token", std::uint64_t{config.max_sessions_per_token()}, "max_sessions",
                   std::uint64_t{config.max_sessions()}}}) {
    if (share_value > whole_value) {
      return std::string(share) + ": must be at most " + whole + " (" + std::to_string(whole_value) +
             "), got " + std::to_string(share_value);
    }
  }
  if (config.max_event_streams_per_session() > config.max_event_streams()) {
    return "max_event_streams_per_session: must be at most max_event_streams (" +
           std::to_string(config.max_event_streams()) + "), got " +
           std::to_string(config.max_event_streams_per_session());
  }
  if (auto e = validate_point_mass(config.simulated_point_mass()); !e.empty()) return e;
  if (config.real_time().fifo_priority() < 1 || config.real_time().fifo_priority() > 99) {
    return "real_time.fifo_priority: must be 1 to 99";
  }
  const int cpus = static_cast<int>(std::thread::hardware_concurrency());
  if (config.real_time().has_cpu() &&
      (config.real_time().cpu() < -1 || (cpus > 0 && config.real_time().cpu() >= cpus))) {
    return "real_time.cpu: must be -1 (no pinning) or 0 to " + std::to_string(cpus - 1) + ", got " +
           std::to_string(config.real_time().cpu());
  }
  if (config.real_time().sender_cpu() < kSenderOnLoopCpu ||
      (cpus > 0 && config.real_time().sender_cpu() >= cpus)) {
    return "real_time.sender_cpu: must be -2 (the loop's), -1 (no pinning) or 0 to " +
           std::to_string(cpus - 1) + ", got " + std::to_string(config.real_time().sender_cpu());
  }
  if (config.real_time().sender_priority() < 0 ||
      config.real_time().sender_priority() >= config.real_time().fifo_priority()) {
    return "real_time.sender_priority: must be 0 (normal scheduling) or 1 to fifo_priority − 1 (" +
           std::to_string(config.real_time().fifo_priority() - 1) + "), got " +
           std::to_string(config.real_time().sender_priority());
  }
  const double period_us = 1e6 / config.loop_rate_hz();
  if (config.real_time().spin_us() >= period_us) {
    return "real_time.spin_us: must be shorter than the loop period (" +
           std::to_string(period_us) + " us)";
  }
  if (auto e = validate_device(config); !e.empty()) return e;
  if (!std::isfinite(config.session_force_budget()) || config.session_force_budget() < 0.0) {
    return "session_force_budget: must be 0 (none) or a positive force in N, got " +
           std::to_string(config.session_force_budget());
  }
  const v1::PassivityConfig& passivity = config.passivity();
  if (!std::isfinite(passivity.max_damping()) || passivity.max_damping() < 0.0 ||
      passivity.max_damping() > 1e5) {
    return "passivity.max_damping: must be 0 (default) to 100000 N*s/m";
  }
  if (!std::isfinite(passivity.velocity_threshold()) || passivity.velocity_threshold() < 0.0 ||
      passivity.velocity_threshold() > 1.0) {
    return "passivity.velocity_threshold: must be 0 (default) to 1 m/s";
  }
  schema::SceneLimits limits;
  engine::HandInput hand;
  if (auto e = schema::to_hand_input(config.initial_operator(), "initial_operator", limits, hand);
      !e.empty()) {
    return e;
  }
  return validate_scene(config.initial_scene(), "initial_scene");
}

std::string validate_scene(const v1::Scene& scene, const std::string& prefix) {
  schema::SceneSpecs ignored;
  return schema::to_scene_specs(scene, prefix.empty() ? "" : prefix + ".", schema::SceneLimits{}, ignored);
}

v1::ServerConfig parse_config(const std::string& json, const std::string& source_name,
                              const ConfigEdit& edit) {
  v1::ServerConfig config;
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;
  const auto status = google::protobuf::util::JsonStringToMessage(json, &config, options);
  if (!status.ok()) {
    throw ConfigError(source_name + ": not a valid ServerConfig: " + std::string(status.message()));
  }
  fill_defaults(config);
  if (edit) edit(config);
  if (auto error = validate(config); !error.empty()) throw ConfigError(source_name + ": " + error);
  return config;
}

v1::ServerConfig load_config_file(const std::string& path, const ConfigEdit& edit) {
  std::string text;
  if (std::string error = io::read_bounded_file(path, io::kMaxConfigFileBytes, "a configuration file", text);
      !error.empty()) {
    throw ConfigError("--config " + error);
  }
  return parse_config(text, path, edit);
}

v1::Scene load_scene_file(const std::string& path) {
  v1::Scene scene;
  if (const std::string error = io::read_scene_file(path, scene); !error.empty()) throw ConfigError(error);
  if (auto error = validate_scene(scene, ""); !error.empty()) throw ConfigError(path + ": " + error);
  return scene;
}

std::string to_json(const v1::ServerConfig& config) {
  google::protobuf::util::JsonPrintOptions options;
  options.add_whitespace = true;
  options.always_print_primitive_fields = true;
  options.preserve_proto_field_names = true;
  std::string out;
  (void)google::protobuf::util::MessageToJsonString(config, &out, options);
  return out;
}

}  // namespace haptic::config
