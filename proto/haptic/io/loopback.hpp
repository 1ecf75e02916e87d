#pragma once
// Whether an address is this host's own, decided the same way by the SDK (a token is sent in
// clear only to loopback), the federation (an interface off this host needs DDS Security) and the
// server's own address checks.

#include <string_view>

#include <sys/socket.h>

namespace haptic::io {

/// An AF_INET or AF_INET6 address in 127.0.0.0/8, ::1, or ::ffff:127.0.0.0/104 (IPv4-mapped).
bool is_loopback_address(const sockaddr* address);

/// Whether `host` names this host without asking a resolver: "localhost" (any case), or a
/// numeric IPv4 or IPv6 address (brackets allowed) that is_loopback_address. Any other name is
/// not, whatever it might resolve to ("127.example.com" is a name, and could be anywhere).
bool is_loopback_literal(std::string_view host);

}  // namespace haptic::io
