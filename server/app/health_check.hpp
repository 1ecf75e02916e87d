#pragma once
// hapticd --health-check: is a server's control plane answering? A fresh connection every time
// (so a server whose listener has gone deaf is reported, not hidden behind an old connection),
// and the standard gRPC health service (grpc.health.v1.Health/Check), as container runtimes,
// systemd scripts and grpc_health_probe expect.

#include <chrono>
#include <string>

namespace haptic::app {

/// True when the server at `address` ("host:port") answers SERVING within `timeout`; otherwise
/// false with `why` saying what happened. With `ca_file` (PEM), over TLS trusting that CA.
bool check_health(const std::string& address, std::chrono::milliseconds timeout, std::string& why,
                  const std::string& ca_file = {});

}  // namespace haptic::app
