#pragma once
// The control plane's TLS, terminated by hapticd itself (OpenSSL): the server's certificate and
// key, and with a client CA mutual TLS (a client must present a certificate that CA signed).
// ALPN offers "h2" only, as gRPC's clients require. TLS 1.2 and 1.3; no renegotiation.
//
// hapticd terminates TLS instead of gRPC because gRPC 1.51 takes TLS connections only on its own
// listener, where none of the control listener's caps, deadlines or out-of-descriptor recovery
// apply (docs/deployment.md, "Connections"); the plaintext side goes to gRPC over a socket pair.

#include <memory>
#include <string>

struct ssl_ctx_st;
struct ssl_st;

namespace haptic::net {

struct TlsServerMaterial {
  std::string cert_pem;       // the server's certificate chain, leaf first
  std::string key_pem;        // its private key
  std::string client_ca_pem;  // empty: no client certificate asked for
  /// The one application protocol the server selects by ALPN: "h2" for gRPC, "http/1.1" for the
  /// HTTP face (a client offering neither fails the handshake; one offering none is served).
  std::string alpn = "h2";
};

class TlsServerContext {
 public:
  /// Throws std::runtime_error naming what is wrong ("security.tls: the private key does not
  /// match the certificate", "security.tls.client_ca_file: no certificate in it").
  explicit TlsServerContext(const TlsServerMaterial& material);
  ~TlsServerContext();
  TlsServerContext(const TlsServerContext&) = delete;
  TlsServerContext& operator=(const TlsServerContext&) = delete;

  /// A server-side connection over the non-blocking socket `fd` (not owned); nullptr when OpenSSL
  /// cannot make one (out of memory).
  ssl_st* new_connection(int fd) const;
  bool mutual() const { return mutual_; }
  /// OpenSSL's context (for Asio's TLS streams on the HTTP face).
  ssl_ctx_st* native() const { return context_; }

 private:
  ssl_ctx_st* context_ = nullptr;
  bool mutual_ = false;
  std::string alpn_wire_;  // the ALPN protocol in its wire form: a length byte, then the name
};

/// OpenSSL's queued errors for this thread as one line ("...: certificate verify failed"),
/// clearing the queue; `fallback` when there are none.
std::string take_tls_errors(const std::string& fallback);

}  // namespace haptic::net
