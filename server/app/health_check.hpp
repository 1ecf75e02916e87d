#pragma once
// hapticd --health-check: is a server's control plane answering? A fresh connection every time
// (so a server whose listener has gone deaf is reported, not hidden behind an old connection),
// and the standard gRPC health service (grpc.health.v1.Health/Check), as container runtimes,
// systemd scripts and grpc_health_probe expect.

#include <chrono>
#include <cstdint>
#include <string>

namespace haptic::app {

/// How --health-check speaks to a server with TLS: the CA its certificate comes from, and for
/// mutual TLS a client certificate and key (PEM files). Empty ca_file: plaintext.
struct HealthTls {
  std::string ca_file;
  std::string cert_file;
  std::string key_file;
};

/// True when the server at `address` ("host:port") answers SERVING within `timeout`; otherwise
/// false with `why` saying what happened.
bool check_health(const std::string& address, std::chrono::milliseconds timeout, std::string& why,
                  const HealthTls& tls = {});

/// Where a process on the same host dials a control plane bound to `bound_address` ("host:port",
/// the port ignored) now listening on `port`: a wildcard host (0.0.0.0, [::], none) is reached on
/// loopback, any other host as it is.
std::string local_dial_address(const std::string& bound_address, std::uint16_t port);

/// The "grpc_address" of a ready file hapticd wrote (--ready-file); empty, with `why` saying what
/// was wrong, when the file is missing or has none.
std::string address_from_ready_file(const std::string& path, std::string& why);

}  // namespace haptic::app
