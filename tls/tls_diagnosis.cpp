#include "tls_diagnosis.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <grpc/support/log.h>
#include <netdb.h>
#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/ssl.h>
#include <openssl/x509v3.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <ctime>
#include <memory>
#include <mutex>

namespace haptic::detail {
namespace {

constexpr char kHttp2Preface[] = "PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n";

struct Target {
  std::string host;
  std::string port;
};

/// The host and port of a gRPC target: host:port, [v6]:port, dns:host:port, dns:///host:port, the
/// first member of an ipv4:/ipv6: list; none for unix: and unix-abstract: targets.
bool parse_target(std::string address, Target& target) {
  if (address.rfind("unix", 0) == 0) return false;
  for (const char* scheme : {"dns:///", "dns:", "ipv4:", "ipv6:"}) {
    const std::string prefix(scheme);
    if (address.rfind(prefix, 0) == 0) {
      address = address.substr(prefix.size());
      break;
    }
  }
  address = address.substr(0, address.find(','));
  const auto colon = address.rfind(':');
  if (colon == std::string::npos || colon + 1 == address.size()) return false;
  target.port = address.substr(colon + 1);
  target.host = address.substr(0, colon);
  if (target.host.size() >= 2 && target.host.front() == '[' && target.host.back() == ']') {
    target.host = target.host.substr(1, target.host.size() - 2);
  }
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

struct X509Free {
  void operator()(X509* certificate) const { X509_free(certificate); }
};
using Certificate = std::unique_ptr<X509, X509Free>;

struct SslFree {
  void operator()(SSL* ssl) const { SSL_free(ssl); }
  void operator()(SSL_CTX* context) const { SSL_CTX_free(context); }
};

/// What the handshake showed, filled in by OpenSSL's callbacks.
struct Observed {
  bool certificate_requested = false;
  Certificate server_certificate;  ///< the leaf the server sent, kept even when it fails to verify
};

/// Set by the client-certificate callback: the server asked for a certificate.
int note_certificate_request(SSL* ssl, X509** /*certificate*/, EVP_PKEY** /*key*/) {
  static_cast<Observed*>(SSL_get_app_data(ssl))->certificate_requested = true;
  return 0;  // none to give
}

/// Keeps the server's certificate for the message; OpenSSL's own verdict stands.
int keep_server_certificate(int preverified, X509_STORE_CTX* store) {
  auto* ssl = static_cast<SSL*>(X509_STORE_CTX_get_ex_data(store, SSL_get_ex_data_X509_STORE_CTX_idx()));
  auto* observed = static_cast<Observed*>(SSL_get_app_data(ssl));
  X509* leaf = X509_STORE_CTX_get0_cert(store);
  if (observed != nullptr && !observed->server_certificate && leaf != nullptr && X509_up_ref(leaf) == 1) {
    observed->server_certificate.reset(leaf);
  }
  return preverified;
}

Certificate read_certificate(const std::string& path) {
  BIO* file = BIO_new_file(path.c_str(), "r");
  if (file == nullptr) return nullptr;
  Certificate certificate(PEM_read_bio_X509(file, nullptr, nullptr, nullptr));
  BIO_free(file);
  return certificate;
}

/// "2020-02-01 00:00:00 UTC".
std::string utc_text(const ASN1_TIME* time) {
  std::tm parts{};
  if (time == nullptr || ASN1_TIME_to_tm(time, &parts) != 1) return "an unreadable date";
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S UTC", &parts);
  return text;
}

std::string now_text() {
  const std::time_t now = std::time(nullptr);
  std::tm parts{};
  gmtime_r(&now, &parts);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S UTC", &parts);
  return text;
}

/// "CN=hapticd test CA".
std::string name_text(const X509_NAME* name) {
  BIO* memory = BIO_new(BIO_s_mem());
  if (memory == nullptr) return {};
  X509_NAME_print_ex(memory, name, 0, XN_FLAG_RFC2253);
  char* data = nullptr;
  const long size = BIO_get_mem_data(memory, &data);
  std::string text(data, static_cast<std::size_t>(size > 0 ? size : 0));
  BIO_free(memory);
  return text;
}

/// The DNS names and IP addresses in a certificate's subjectAltName, comma-separated.
std::string names_text(X509* certificate) {
  auto* names = static_cast<GENERAL_NAMES*>(X509_get_ext_d2i(certificate, NID_subject_alt_name, nullptr, nullptr));
  std::string text;
  for (int i = 0; names != nullptr && i < sk_GENERAL_NAME_num(names); ++i) {
    const GENERAL_NAME* name = sk_GENERAL_NAME_value(names, i);
    std::string one;
    if (name->type == GEN_DNS) {
      one.assign(reinterpret_cast<const char*>(ASN1_STRING_get0_data(name->d.dNSName)),
                 static_cast<std::size_t>(ASN1_STRING_length(name->d.dNSName)));
    } else if (name->type == GEN_IPADD) {
      char address[INET6_ADDRSTRLEN] = {};
      const int length = ASN1_STRING_length(name->d.iPAddress);
      const unsigned char* bytes = ASN1_STRING_get0_data(name->d.iPAddress);
      if ((length == 4 || length == 16) &&
          ::inet_ntop(length == 4 ? AF_INET : AF_INET6, bytes, address, sizeof address) != nullptr) {
        one = address;
      }
    }
    if (one.empty()) continue;
    text += (text.empty() ? "" : ", ") + one;
  }
  GENERAL_NAMES_free(names);
  return text.empty() ? "no name in subjectAltName" : text;
}

/// What is wrong with the client's own certificate before any byte is sent: its dates.
std::string check_own_certificate(const TlsAttempt& attempt) {
  if (!attempt.tls || attempt.cert_file.empty()) return {};
  const Certificate certificate = read_certificate(attempt.cert_file);
  if (!certificate) return {};
  const std::string where = "the client certificate in " + attempt.names.certificate + " '" + attempt.cert_file + "'";
  if (X509_cmp_current_time(X509_get0_notAfter(certificate.get())) < 0) {
    return where + " expired on " + utc_text(X509_get0_notAfter(certificate.get())) +
           ": give a current one (its CA renews it)";
  }
  if (X509_cmp_current_time(X509_get0_notBefore(certificate.get())) > 0) {
    return where + " is not valid before " + utc_text(X509_get0_notBefore(certificate.get())) +
           " (this host's clock says " + now_text() + "): give one valid now, or set this host's clock right";
  }
  return {};
}

std::string certificate_wanted(const TlsAttempt& attempt) {
  return "the server asks for a client certificate (mutual TLS): give one with " + attempt.names.certificate +
         " and its key with " + attempt.names.key;
}

/// The server's certificate failed to verify: why, from OpenSSL's verdict and the certificate.
std::string server_certificate_refused(const TlsAttempt& attempt, long verified, X509* server,
                                       const std::string& name) {
  if (verified == X509_V_ERR_HOSTNAME_MISMATCH || verified == X509_V_ERR_IP_ADDRESS_MISMATCH) {
    const std::string names = server != nullptr ? names_text(server) : "other names";
    return "the server's certificate carries " + names + ", not '" + name + "': " + attempt.names.server_name;
  }
  if (verified == X509_V_ERR_CERT_HAS_EXPIRED && server != nullptr) {
    return "the server's certificate expired on " + utc_text(X509_get0_notAfter(server)) +
           ": its operator must renew it (the server's security.tls.cert_file); no setting on this side fixes it";
  }
  if (verified == X509_V_ERR_CERT_NOT_YET_VALID && server != nullptr) {
    return "the server's certificate is not valid before " + utc_text(X509_get0_notBefore(server)) +
           " (this host's clock says " + now_text() +
           "): set the clock right, here or on the server, or have its operator reissue it";
  }
  const Certificate ca = read_certificate(attempt.ca_file);
  const std::string ca_holds = ca ? " (which holds '" + name_text(X509_get_subject_name(ca.get())) + "')" : "";
  const std::string issuer = server != nullptr ? "'" + name_text(X509_get_issuer_name(server)) + "'" : "a CA";
  return "the server's certificate is signed by " + issuer + ", which " + attempt.names.ca + " '" +
         attempt.ca_file + "'" + ca_holds + " does not trust (" + X509_verify_cert_error_string(verified) +
         "): give that CA's certificate with " + attempt.names.ca;
}

}  // namespace

std::string diagnose_tls_mismatch(const TlsAttempt& attempt, std::chrono::milliseconds timeout) {
  if (std::string own = check_own_certificate(attempt); !own.empty()) return own;
  Target target;
  if (!parse_target(attempt.address, target)) return {};
  const int fd = connect_to(target, timeout);
  if (fd < 0) return {};
  const std::unique_ptr<SSL_CTX, SslFree> context(SSL_CTX_new(TLS_client_method()));
  if (!context) {
    ::close(fd);
    return {};
  }
  SSL_CTX_set_min_proto_version(context.get(), TLS1_2_VERSION);
  static const unsigned char kAlpn[] = {2, 'h', '2'};
  SSL_CTX_set_alpn_protos(context.get(), kAlpn, sizeof kAlpn);
  const bool with_certificate = attempt.tls && !attempt.cert_file.empty();
  const std::string name = attempt.tls && !attempt.server_name.empty() ? attempt.server_name : target.host;
  if (attempt.tls) {
    SSL_CTX_load_verify_locations(context.get(), attempt.ca_file.c_str(), nullptr);
    SSL_CTX_set_verify(context.get(), SSL_VERIFY_PEER, keep_server_certificate);
    if (with_certificate) {
      SSL_CTX_use_certificate_chain_file(context.get(), attempt.cert_file.c_str());
      SSL_CTX_use_PrivateKey_file(context.get(), attempt.key_file.c_str(), SSL_FILETYPE_PEM);
    }
  } else {
    SSL_CTX_set_verify(context.get(), SSL_VERIFY_NONE, nullptr);
  }
  SSL_CTX_set_client_cert_cb(context.get(), note_certificate_request);
  const std::unique_ptr<SSL, SslFree> ssl(SSL_new(context.get()));
  if (!ssl) {
    ::close(fd);
    return {};
  }
  Observed observed;
  SSL_set_app_data(ssl.get(), &observed);
  SSL_set_fd(ssl.get(), fd);
  in6_addr numeric{};
  const bool is_address = ::inet_pton(AF_INET, name.c_str(), &numeric) == 1 ||
                          ::inet_pton(AF_INET6, name.c_str(), &numeric) == 1;
  if (!is_address) SSL_set_tlsext_host_name(ssl.get(), name.c_str());
  if (attempt.tls) {
    // An address is matched against the certificate's IP entries, a name against its DNS ones.
    if (is_address) {
      X509_VERIFY_PARAM_set1_ip_asc(SSL_get0_param(ssl.get()), name.c_str());
    } else {
      SSL_set1_host(ssl.get(), name.c_str());
    }
  }

  ERR_clear_error();
  const int connected = SSL_connect(ssl.get());
  std::string reason = last_reason();
  std::string hint;
  if (!attempt.tls) {
    if (connected == 1 || is_alert_from_the_server(reason)) {
      hint = "the server speaks TLS: " + attempt.names.turn_on;
      if (observed.certificate_requested) {
        hint += ", and a client certificate (" + attempt.names.certificate + ", " + attempt.names.key +
                "): it asks for one (mutual TLS)";
      }
    }
  } else if (connected != 1) {
    const long verified = SSL_get_verify_result(ssl.get());
    if (verified != X509_V_OK) {
      hint = server_certificate_refused(attempt, verified, observed.server_certificate.get(), name);
    } else if (not_tls(reason) || reason.empty()) {
      hint = "the server does not speak TLS (a plaintext server): " + attempt.names.turn_off +
             ", or have its operator turn on security.tls";
    } else if (observed.certificate_requested && !with_certificate) {
      hint = certificate_wanted(attempt);
    } else {
      hint = "the TLS handshake fails: " + reason;
    }
  } else if (observed.certificate_requested && !with_certificate) {
    hint = certificate_wanted(attempt);
  } else if (with_certificate) {
    // TLS 1.3: the server's verdict on the client certificate comes after the handshake. A server
    // that takes it answers the HTTP/2 preface with its SETTINGS; one that refuses it sends an
    // alert or (as gRPC often does, the alert never flushed) just closes the connection.
    char byte = 0;
    const bool sent = SSL_write(ssl.get(), kHttp2Preface, sizeof kHttp2Preface - 1) > 0;
    errno = 0;
    const int read = SSL_read(ssl.get(), &byte, 1);
    const int error = read > 0 ? SSL_ERROR_NONE : SSL_get_error(ssl.get(), read);
    const bool timed_out = error == SSL_ERROR_WANT_READ ||
                           (error == SSL_ERROR_SYSCALL && (errno == EAGAIN || errno == EWOULDBLOCK));
    reason = last_reason();
    if (read <= 0 && !timed_out) {
      const Certificate own = read_certificate(attempt.cert_file);
      const std::string issuer = own ? ", signed by '" + name_text(X509_get_issuer_name(own.get())) + "'" : "";
      const std::string how = is_alert_from_the_server(reason) ? reason
                              : sent ? "it closed the connection on receiving it"
                                     : "it closed the connection during the handshake";
      hint = "the server refuses the client certificate in " + attempt.names.certificate + " '" +
             attempt.cert_file + "'" + issuer + " (" + how + "): give one signed by the CA the server trusts "
             "for clients (its security.tls.client_ca_file)";
    }
  }
  ::close(fd);
  ERR_clear_error();
  return hint;
}

void quiet_grpc_log_unless_asked() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (std::getenv("GRPC_VERBOSITY") != nullptr) return;
    gpr_set_log_function([](gpr_log_func_args* /*args*/) {});
  });
}

}  // namespace haptic::detail
