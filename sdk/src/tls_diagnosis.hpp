#pragma once
// Why a first connection to the control plane failed, when the reason is a TLS mismatch that
// gRPC reports only as "Connection reset by peer", "certificate verify failed" or a decryption
// error: one TLS handshake of the SDK's own (OpenSSL, the same CA, certificate and name as the
// ClientConfig), after gRPC's attempt failed, never before. It sends a ClientHello (and with a
// client certificate the HTTP/2 preface, to hear the server's verdict on it), nothing else.

#include <chrono>
#include <string>

#include "haptic/client.hpp"

namespace haptic::detail {

/// What to fix, in the ClientConfig's terms ("the server speaks TLS: give ClientConfig::tls ...",
/// "the server asks for a client certificate (mutual TLS): give tls.cert_file and tls.key_file",
/// "the server's certificate is not signed by the CA in tls.ca_file '...': ...", "the server does
/// not speak TLS ...: drop ClientConfig::tls"); empty when the handshake shows nothing wrong, or
/// the server cannot be reached within `timeout`.
std::string diagnose_tls_mismatch(const ClientConfig& config, std::chrono::milliseconds timeout);

}  // namespace haptic::detail
