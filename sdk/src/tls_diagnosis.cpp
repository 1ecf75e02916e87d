#include "tls_diagnosis.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <openssl/err.h>
#include <openssl/ssl.h>
#include <openssl/x509v3.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <memory>

#include "client_core.hpp"

namespace haptic::detail {
namespace {

constexpr char kHttp2Preface[] = "PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n";

struct Target {
  std::string host;
  std::string port;
};

/// The host and port of the client's server address; none for "unix:" targets.
bool parse_target(const std::string& address, Target& target) {
  if (address.rfind("unix:", 0) == 0) return false;
  const auto colon = address.rfind(':');
  if (colon == std::string::npos || colon + 1 == address.size()) return false;
  target.port = address.substr(colon + 1);
  target.host = host_of(address);
  return !target.host.empty();
}

/// A blocking TCP connection to `target` with `timeout` on connecting, sending and receiving;
/// -1 if none can be made.
int connect_to(const Target& target, std::chrono::milliseconds timeout) {
  addrinfo hints{};
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  if (::getaddrinfo(target.host.c_str(), target.port.c_str(), &hints, &found) != 0) return -1;
  const std::unique_ptr<addrinfo, decltype(&::freeaddrinfo)> owned(found, &::freeaddrinfo);
  for (const addrinfo* a = found; a != nullptr; a = a->ai_next) {
    const int fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC | SOCK_NONBLOCK, a->ai_protocol);
    if (fd < 0) continue;
    int result = ::connect(fd, a->ai_addr, a->ai_addrlen);
    if (result != 0 && errno == EINPROGRESS) {
      pollfd p{fd, POLLOUT, 0};
      int error = 0;
      socklen_t length = sizeof error;
      if (::poll(&p, 1, static_cast<int>(timeout.count())) == 1 &&
          ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &error, &length) == 0 && error == 0) {
        result = 0;
      }
    }
    if (result == 0) {
      ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
      timeval limit{static_cast<time_t>(timeout.count() / 1000),
                    static_cast<suseconds_t>((timeout.count() % 1000) * 1000)};
      ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &limit, sizeof limit);
      ::setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &limit, sizeof limit);
      return fd;
    }
    ::close(fd);
  }
  return -1;
}

/// OpenSSL's reason for the last failure ("certificate verify failed"), the queue cleared.
std::string last_reason() {
  std::string reason;
  while (const unsigned long code = ERR_get_error()) {
    if (const char* text = ERR_reason_error_string(code)) reason = text;
  }
  return reason;
}

bool is_alert_from_the_server(const std::string& reason) {
  return reason.find("alert") != std::string::npos;
}

/// The reasons OpenSSL gives when the bytes that came back are not TLS records.
bool not_tls(const std::string& reason) {
  return reason == "wrong version number" || reason == "packet length too long" ||
         reason == "record layer failure" || reason == "unexpected eof while reading";
}

/// Set by the client-certificate callback: the server asked for a certificate.
int note_certificate_request(SSL* ssl, X509** /*certificate*/, EVP_PKEY** /*key*/) {
  *static_cast<bool*>(SSL_get_app_data(ssl)) = true;
  return 0;  // none to give
}

struct SslDeleter {
  void operator()(SSL* ssl) const { SSL_free(ssl); }
  void operator()(SSL_CTX* context) const { SSL_CTX_free(context); }
};

}  // namespace

std::string diagnose_tls_mismatch(const ClientConfig& config, std::chrono::milliseconds timeout) {
  Target target;
  if (!parse_target(config.server_address, target)) return {};
  const int fd = connect_to(target, timeout);
  if (fd < 0) return {};
  const std::unique_ptr<SSL_CTX, SslDeleter> context(SSL_CTX_new(TLS_client_method()));
  if (!context) {
    ::close(fd);
    return {};
  }
  SSL_CTX_set_min_proto_version(context.get(), TLS1_2_VERSION);
  static const unsigned char kAlpn[] = {2, 'h', '2'};
  SSL_CTX_set_alpn_protos(context.get(), kAlpn, sizeof kAlpn);
  const bool with_tls = config.tls.has_value();
  const bool with_certificate = with_tls && !config.tls->cert_file.empty();
  const std::string name = with_tls && !config.tls->server_name.empty() ? config.tls->server_name : target.host;
  if (with_tls) {
    SSL_CTX_load_verify_locations(context.get(), config.tls->ca_file.c_str(), nullptr);
    SSL_CTX_set_verify(context.get(), SSL_VERIFY_PEER, nullptr);
    if (with_certificate) {
      SSL_CTX_use_certificate_chain_file(context.get(), config.tls->cert_file.c_str());
      SSL_CTX_use_PrivateKey_file(context.get(), config.tls->key_file.c_str(), SSL_FILETYPE_PEM);
    }
  } else {
    SSL_CTX_set_verify(context.get(), SSL_VERIFY_NONE, nullptr);
  }
  SSL_CTX_set_client_cert_cb(context.get(), note_certificate_request);
  const std::unique_ptr<SSL, SslDeleter> ssl(SSL_new(context.get()));
  if (!ssl) {
    ::close(fd);
    return {};
  }
  bool certificate_requested = false;
  SSL_set_app_data(ssl.get(), &certificate_requested);
  SSL_set_fd(ssl.get(), fd);
  in6_addr numeric{};
  const bool is_address = ::inet_pton(AF_INET, name.c_str(), &numeric) == 1 ||
                          ::inet_pton(AF_INET6, name.c_str(), &numeric) == 1;
  if (!is_address) SSL_set_tlsext_host_name(ssl.get(), name.c_str());
  if (with_tls) SSL_set1_host(ssl.get(), name.c_str());

  ERR_clear_error();
  const int connected = SSL_connect(ssl.get());
  std::string reason = last_reason();
  std::string hint;
  if (!with_tls) {
    if (connected == 1 || is_alert_from_the_server(reason)) {
      hint = "the server speaks TLS: give ClientConfig::tls (TlsOptions with the CA that signed its "
             "certificate; hapticctl --ca)";
      if (certificate_requested) hint += ", and a client certificate: it asks for one (mutual TLS)";
    }
  } else if (connected != 1) {
    const long verified = SSL_get_verify_result(ssl.get());
    if (verified == X509_V_ERR_HOSTNAME_MISMATCH) {
      hint = "the server's certificate does not carry the name '" + name +
             "': connect by a name it carries, or set tls.server_name to one";
    } else if (verified != X509_V_OK) {
      hint = "the server's certificate is not trusted by the CA in tls.ca_file '" + config.tls->ca_file +
             "' (" + X509_verify_cert_error_string(verified) + "): give the CA that signed it";
    } else if (not_tls(reason) || reason.empty()) {
      hint = "the server does not speak TLS (a plaintext server?): drop ClientConfig::tls, or ask "
             "its operator to turn on security.tls";
    } else if (certificate_requested && !with_certificate) {
      hint = "the server asks for a client certificate (mutual TLS): give tls.cert_file and "
             "tls.key_file (hapticctl --cert, --key)";
    } else {
      hint = "the TLS handshake fails: " + reason;
    }
  } else if (certificate_requested && !with_certificate) {
    hint = "the server asks for a client certificate (mutual TLS): give tls.cert_file and "
           "tls.key_file (hapticctl --cert, --key)";
  } else if (with_certificate) {
    // TLS 1.3: the server's verdict on the client certificate comes after the handshake.
    char byte = 0;
    if (SSL_write(ssl.get(), kHttp2Preface, sizeof kHttp2Preface - 1) > 0 && SSL_read(ssl.get(), &byte, 1) <= 0) {
      reason = last_reason();
      if (is_alert_from_the_server(reason)) {
        hint = "the server refuses the client certificate in tls.cert_file '" + config.tls->cert_file +
               "' (" + reason + "): give one its client CA signed";
      }
    }
  }
  ::close(fd);
  ERR_clear_error();
  return hint;
}

}  // namespace haptic::detail
