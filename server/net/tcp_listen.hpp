#pragma once
// Listening TCP sockets for "host:port" ("[v6]:port", "host" alone: port 0), shared by the
// control plane's listener and the metrics endpoint.

#include <sys/socket.h>

#include <cstdint>
#include <string>
#include <vector>

namespace haptic::net {

struct ListeningSockets {
  std::vector<int> fds;   // non-blocking, close-on-exec; one per address the host resolves to
  std::uint16_t port = 0; // the port all of them listen on (the first one's pick for port 0)
};

/// Binds and listens on every address `address` resolves to, all on one port. SO_REUSEADDR only
/// (a restart need not wait out TIME_WAIT), never SO_REUSEPORT, so a second server cannot quietly
/// share the port. Throws std::runtime_error "cannot listen for <what> on <address>: <why>", or
/// "<field> '<address>': <why>" when the address does not resolve.
ListeningSockets listen_tcp(const std::string& address, const std::string& what,
                            const std::string& field);

/// The host an accepted connection comes from, as accept() gave its address (IPv4-mapped IPv6
/// written as IPv4, the data plane's form: peer_host()).
std::string host_of_peer(const sockaddr_storage& address, socklen_t length);

}  // namespace haptic::net
