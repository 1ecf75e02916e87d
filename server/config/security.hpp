#pragma once
// The control plane's security settings (ServerConfig.security): TLS files and bearer tokens,
// checked with errors that name the field, and read at start (docs/deployment.md).

#include <string>

#include "haptic/v1/config.pb.h"

namespace haptic::config {

/// Empty when `security` is valid (files are not read here), else "security.<field>: …".
std::string validate_security(const v1::SecurityConfig& security);

/// True when the control plane is encrypted and every call must carry a token: what a
/// non-loopback address needs without insecure_remote_access. A tokens_file counts as tokens.
bool secured_for_remote_access(const v1::SecurityConfig& security);

/// What the server needs from the files the settings name.
struct SecurityMaterial {
  bool tls = false;
  std::string cert_pem;       // the server's certificate chain
  std::string key_pem;        // its private key
  std::string client_ca_pem;  // empty: no client certificates asked for
  v1::AccessTokens tokens;    // `tokens` and the tokens_file's, validated together
};

/// Reads the certificate, key, client CA and tokens files. Throws ConfigError naming the field
/// and the file ("security.tls.key_file: cannot read 'x.pem': No such file or directory"), or a
/// token in the file that is not valid or repeats one ("security.tokens_file 't.json':
/// tokens[1].token: …").
SecurityMaterial load_security(const v1::SecurityConfig& security);

}  // namespace haptic::config
