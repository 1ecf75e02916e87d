#pragma once
// Why a first connection to the control plane failed, when the reason is TLS: gRPC reports every
// such failure as "Connection reset by peer", "Endpoint read failed", "certificate verify failed"
// or a decryption error, whatever went wrong. This looks at the client's own certificate first
// (its dates, without the network), then makes one TLS handshake of its own (OpenSSL, the same
// CA, certificate and name), after gRPC's attempt failed, never before. It sends a ClientHello
// (and with a client certificate the HTTP/2 preface, to hear the server's verdict on it), nothing
// else. Used by the SDK (ClientCore) and by `hapticd --health-check`, each naming its own options.

#include <chrono>
#include <string>

namespace haptic::detail {

/// How the caller's user sets each thing the answer may tell them to change.
struct TlsSettingNames {
  std::string turn_on;      ///< the fix when the server speaks TLS ("turn it on with ClientConfig::tls ...")
  std::string turn_off;     ///< the fix when it does not ("drop ClientConfig::tls (leave out --ca)")
  std::string ca;           ///< the CA file's setting ("tls.ca_file (--ca)")
  std::string certificate;  ///< the client certificate's ("tls.cert_file (--cert)")
  std::string key;          ///< its private key's ("tls.key_file (--key)")
  std::string server_name;  ///< the fix for a name the certificate lacks ("connect by one of them, or ...")
};

/// What the client tried.
struct TlsAttempt {
  std::string address;      ///< gRPC target: host:port, [v6]:port, dns:, ipv4:/ipv6: (first member)
  bool tls = false;
  std::string ca_file;      ///< PEM
  std::string cert_file;    ///< PEM; empty: no client certificate
  std::string key_file;
  std::string server_name;  ///< empty: the address's host
  TlsSettingNames names;
};

/// One line naming the cause and the setting that fixes it ("the client certificate in
/// tls.cert_file '...' expired on 2020-02-01 00:00:00 UTC: ...", "the server's certificate
/// carries the names localhost, 127.0.0.1, not 'other.lab': ...", "the server speaks TLS: ...");
/// empty when nothing about TLS is wrong, or the server cannot be reached within `timeout`.
std::string diagnose_tls_mismatch(const TlsAttempt& attempt, std::chrono::milliseconds timeout);

/// gRPC's own log lines ("E1205 ... Handshake failed ...") say in gRPC's terms what the errors
/// above say in the user's: they are dropped unless GRPC_VERBOSITY is set in the environment, in
/// which case gRPC's own logging stays as it is. Called once per process (later calls do nothing).
void quiet_grpc_log_unless_asked();

}  // namespace haptic::detail
