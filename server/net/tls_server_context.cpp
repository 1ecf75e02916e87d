#include "net/tls_server_context.hpp"

#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/ssl.h>
#include <openssl/x509.h>

#include <stdexcept>

namespace haptic::net {
namespace {

/// Chooses the context's one protocol (`arg`: its ALPN wire form, "h2" for gRPC, RFC 7540 §3.3)
/// from the client's list, or fails the handshake: gRPC clients refuse a server that selects no
/// protocol, and a browser offering h2 alone must not be taken for an HTTP/1.1 client.
int select_protocol(SSL* /*ssl*/, const unsigned char** out, unsigned char* out_length,
                    const unsigned char* offered, unsigned int offered_length, void* arg) {
  const auto* wanted = static_cast<const std::string*>(arg);
  unsigned char* chosen = nullptr;
  if (SSL_select_next_proto(&chosen, out_length, reinterpret_cast<const unsigned char*>(wanted->data()),
                            static_cast<unsigned int>(wanted->size()), offered,
                            offered_length) != OPENSSL_NPN_NEGOTIATED) {
    return SSL_TLSEXT_ERR_ALERT_FATAL;
  }
  *out = chosen;
  return SSL_TLSEXT_ERR_OK;
}

struct BioDeleter {
  void operator()(BIO* bio) const { BIO_free(bio); }
};

std::unique_ptr<BIO, BioDeleter> memory_bio(const std::string& pem) {
  return std::unique_ptr<BIO, BioDeleter>(BIO_new_mem_buf(pem.data(), static_cast<int>(pem.size())));
}

}  // namespace

std::string take_tls_errors(const std::string& fallback) {
  std::string line;
  while (const unsigned long code = ERR_get_error()) {
    char text[256];
    ERR_error_string_n(code, text, sizeof text);
    if (!line.empty()) line += "; ";
    // "error:0A000086:SSL routines::certificate verify failed": keep the reason only.
    const char* reason = ERR_reason_error_string(code);
    line += reason != nullptr ? reason : text;
  }
  return line.empty() ? fallback : line;
}

TlsServerContext::TlsServerContext(const TlsServerMaterial& material)
    : mutual_(!material.client_ca_pem.empty()) {
  ERR_clear_error();
  context_ = SSL_CTX_new(TLS_server_method());
  if (context_ == nullptr) throw std::runtime_error("security.tls: " + take_tls_errors("cannot make a TLS context"));
  const auto fail = [this](const std::string& what) {
    const std::string why = take_tls_errors("");
    SSL_CTX_free(context_);
    context_ = nullptr;
    throw std::runtime_error(what + (why.empty() ? "" : " (" + why + ")"));
  };
  SSL_CTX_set_min_proto_version(context_, TLS1_2_VERSION);
  // A client that closes its TCP connection without close_notify (most do) has ended its stream,
  // not failed: what it sent before still goes to gRPC.
  SSL_CTX_set_options(context_, SSL_OP_NO_RENEGOTIATION | SSL_OP_CIPHER_SERVER_PREFERENCE |
                                    SSL_OP_IGNORE_UNEXPECTED_EOF);
  // Partial writes with a buffer that may move between retries: the pump hands SSL_write the
  // front of its queue, wherever that is after a compaction.
  SSL_CTX_set_mode(context_, SSL_MODE_ENABLE_PARTIAL_WRITE | SSL_MODE_ACCEPT_MOVING_WRITE_BUFFER |
                                 SSL_MODE_RELEASE_BUFFERS);
  // No resumption: a control-plane client connects once and stays; nothing to cache or ticket.
  SSL_CTX_set_session_cache_mode(context_, SSL_SESS_CACHE_OFF);
  SSL_CTX_set_num_tickets(context_, 0);
  alpn_wire_ = std::string(1, static_cast<char>(material.alpn.size())) + material.alpn;
  SSL_CTX_set_alpn_select_cb(context_, select_protocol, &alpn_wire_);

  // The certificate chain: the leaf, then any intermediates in the same PEM.
  auto chain = memory_bio(material.cert_pem);
  X509* leaf = PEM_read_bio_X509_AUX(chain.get(), nullptr, nullptr, nullptr);
  if (leaf == nullptr) fail("security.tls.cert_file: no PEM certificate in it");
  const int used = SSL_CTX_use_certificate(context_, leaf);
  X509_free(leaf);
  if (used != 1) fail("security.tls.cert_file: the certificate cannot be used");
  while (X509* intermediate = PEM_read_bio_X509(chain.get(), nullptr, nullptr, nullptr)) {
    if (SSL_CTX_add0_chain_cert(context_, intermediate) != 1) {
      X509_free(intermediate);
      fail("security.tls.cert_file: an intermediate certificate cannot be used");
    }
  }
  ERR_clear_error();  // the loop above ends on "no start line"

  auto key_bio = memory_bio(material.key_pem);
  EVP_PKEY* key = PEM_read_bio_PrivateKey(key_bio.get(), nullptr, nullptr, nullptr);
  if (key == nullptr) fail("security.tls.key_file: no PEM private key in it (or it is encrypted)");
  const int key_used = SSL_CTX_use_PrivateKey(context_, key);
  EVP_PKEY_free(key);
  if (key_used != 1 || SSL_CTX_check_private_key(context_) != 1) {
    fail("security.tls: the private key does not match the certificate");
  }

  if (mutual_) {
    // Each CA verifies client certificates, and is named in the certificate request so that a
    // client holding several certificates picks the right one.
    X509_STORE* store = SSL_CTX_get_cert_store(context_);
    auto ca_bio = memory_bio(material.client_ca_pem);
    STACK_OF(X509_NAME)* names = sk_X509_NAME_new_null();
    while (X509* ca = PEM_read_bio_X509(ca_bio.get(), nullptr, nullptr, nullptr)) {
      if (X509_STORE_add_cert(store, ca) == 1) sk_X509_NAME_push(names, X509_NAME_dup(X509_get_subject_name(ca)));
      X509_free(ca);
    }
    ERR_clear_error();
    if (sk_X509_NAME_num(names) == 0) {
      sk_X509_NAME_free(names);
      fail("security.tls.client_ca_file: no PEM certificate in it");
    }
    SSL_CTX_set_client_CA_list(context_, names);
    SSL_CTX_set_verify(context_, SSL_VERIFY_PEER | SSL_VERIFY_FAIL_IF_NO_PEER_CERT, nullptr);
  }
}

TlsServerContext::~TlsServerContext() { SSL_CTX_free(context_); }

ssl_st* TlsServerContext::new_connection(int fd) const {
  SSL* ssl = SSL_new(context_);
  if (ssl == nullptr) return nullptr;
  if (SSL_set_fd(ssl, fd) != 1) {
    SSL_free(ssl);
    return nullptr;
  }
  SSL_set_accept_state(ssl);
  return ssl;
}

}  // namespace haptic::net
