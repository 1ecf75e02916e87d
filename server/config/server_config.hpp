#pragma once
// hapticd's configuration: protobuf's JSON mapping of haptic.v1.ServerConfig, defaults filled in,
// every value checked with an error that names the field.

#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>

#include "haptic/v1/config.pb.h"

namespace haptic::config {

/// real_time.spin_us's default at `rate_hz`: 200 µs, or 80 % of a shorter period (200 at 4 kHz,
/// 80 at 10 kHz). Measured on the project's VMs (tests/bench/loop_lateness_bench): the loop's p99
/// lateness then matches a busy-spin loop's at 1, 4 and 10 kHz, while the fifth of each period it
/// sleeps keeps it under the kernel's real-time throttle (a loop that never sleeps loses 50 ms a
/// second). Costs spin × rate of the loop's core: a fifth at 1 kHz, four fifths at 4 and 10 kHz.
std::uint32_t default_spin_us(double rate_hz);

/// real_time.sender_cpu's value for "on the loop's CPU" (the default).
inline constexpr int kSenderOnLoopCpu = -2;

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The built-in configuration: real time at 1 kHz, the simulated point mass, gRPC on
/// 127.0.0.1:50051, UDP on 127.0.0.1:50052 (loopback only).
v1::ServerConfig default_config();

/// Changes made to a configuration after its defaults are filled and before it is validated (the
/// command line's overrides: a file's udp_address with --insecure is one valid configuration).
using ConfigEdit = std::function<void(v1::ServerConfig&)>;

/// Parses JSON text (unknown fields are errors), fills defaults, applies `edit`, validates.
/// Throws ConfigError.
v1::ServerConfig parse_config(const std::string& json, const std::string& source_name,
                              const ConfigEdit& edit = {});

/// Reads and parses a file. Throws ConfigError naming the file.
v1::ServerConfig load_config_file(const std::string& path, const ConfigEdit& edit = {});

/// Reads a scene file: protobuf's JSON mapping of haptic.v1.Scene (unknown fields are errors),
/// every object and field validated. Throws ConfigError naming the file and the element
/// ("walls.json: objects[2].impedance.stiffness: …").
v1::Scene load_scene_file(const std::string& path);

/// Empty when every object and field of `scene` is valid, else "<prefix>.objects[i]…: …".
std::string validate_scene(const v1::Scene& scene, const std::string& prefix);

/// Sets every unset (zero) field to its default.
void fill_defaults(v1::ServerConfig& config);

/// Empty when valid, else "<field>: <what is wrong>".
std::string validate(const v1::ServerConfig& config);

/// The host part of a bind address "host:port", "[v6]:port" or a bare host.
std::string host_of_address(const std::string& address);

/// True when every address `host` names is a loopback address (127.0.0.0/8, ::1); false for ""
/// or 0.0.0.0 (every interface) and for names that do not resolve.
bool is_loopback_host(const std::string& host);

/// The configuration as JSON, with defaults shown.
std::string to_json(const v1::ServerConfig& config);

}  // namespace haptic::config
