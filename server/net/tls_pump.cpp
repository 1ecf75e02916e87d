#include "net/tls_pump.hpp"

#include <openssl/err.h>
#include <openssl/ssl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <optional>

#include "net/tls_server_context.hpp"

namespace haptic::net {
namespace {

constexpr std::string_view kHttp2Preface("PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n", kHttp2PrefaceBytes);

/// "TLS: <OpenSSL's reason>" for a failed TLS call, or the socket's own error.
std::string tls_failure(int error, int saved_errno) {
  if (error == SSL_ERROR_SYSCALL) {
    const std::string queued = take_tls_errors("");
    if (!queued.empty()) return "TLS: " + queued;
    return saved_errno == 0 ? "client closed" : std::string("connection: ") + std::strerror(saved_errno);
  }
  if (error == SSL_ERROR_ZERO_RETURN) return "client closed";
  return "TLS: " + take_tls_errors("protocol error");
}

}  // namespace

PrefaceCheck check_http2_preface(std::string_view first_bytes) {
  const std::size_t n = std::min(first_bytes.size(), kHttp2Preface.size());
  if (first_bytes.substr(0, n) != kHttp2Preface.substr(0, n)) return PrefaceCheck::kNotHttp2;
  return n == kHttp2Preface.size() ? PrefaceCheck::kComplete : PrefaceCheck::kSoFar;
}

std::optional<TlsPump::Want> TlsPump::waits_for(int ssl_error) {
  if (ssl_error == SSL_ERROR_WANT_READ) return Want::kReadable;
  if (ssl_error == SSL_ERROR_WANT_WRITE) return Want::kWritable;
  return std::nullopt;
}

void TlsPump::Queue::compact() {
  if (!bytes_) bytes_.reset(new char[kQueueBytes]);  // uninitialized: only what is read is touched
  if (begin_ == 0) return;
  std::memmove(bytes_.get(), bytes_.get() + begin_, end_ - begin_);
  end_ -= begin_;
  begin_ = 0;
}

TlsPump::TlsPump(ssl_st* ssl, int net_fd) : ssl_(ssl), net_fd_(net_fd) {}

TlsPump::~TlsPump() {
  SSL_free(ssl_);
  if (net_fd_ >= 0) ::close(net_fd_);
  if (app_fd_ >= 0) ::close(app_fd_);
}

TlsPump::Stage TlsPump::advance() {
  if (stage_ == Stage::kHandshake) handshake();
  if (stage_ == Stage::kPreface) read_preface();
  if (stage_ == Stage::kOpen) pump();
  return stage_;
}

void TlsPump::attach_app(int app_fd) {
  app_fd_ = app_fd;
  stage_ = Stage::kOpen;
}

TlsPump::Interest TlsPump::interest() const {
  Interest interest;
  if (stage_ == Stage::kClosed || stage_ == Stage::kReadyToServe) return interest;
  interest.net_read = reading_waits_for_ == Want::kReadable || writing_waits_for_ == Want::kReadable;
  interest.net_write = reading_waits_for_ == Want::kWritable || writing_waits_for_ == Want::kWritable;
  if (stage_ == Stage::kOpen) {
    interest.app_read = !app_ended_ && to_net_.size() < kQueueBytes;
    interest.app_write = !to_app_.empty() && !app_refuses_writes_;
  }
  return interest;
}

void TlsPump::close(std::string why) {
  if (stage_ == Stage::kClosed) return;
  why_ = std::move(why);
  stage_ = Stage::kClosed;
  ERR_clear_error();
}

void TlsPump::handshake() {
  ERR_clear_error();
  errno = 0;
  const int result = SSL_do_handshake(ssl_);
  if (result == 1) {
    handshake_completed_ = true;
    reading_waits_for_ = Want::kReadable;
    stage_ = Stage::kPreface;
    return;
  }
  const int saved_errno = errno;
  const int error = SSL_get_error(ssl_, result);
  if (const auto wait = waits_for(error)) {
    reading_waits_for_ = *wait;
  } else {
    close(saved_errno == 0 && error == SSL_ERROR_SYSCALL ? "closed during the TLS handshake"
                                                         : tls_failure(error, saved_errno));
  }
}

void TlsPump::read_preface() {
  while (to_app_.size() < kHttp2PrefaceBytes && read_net()) {
  }
  if (stage_ == Stage::kClosed) return;
  switch (check_http2_preface(std::string_view(to_app_.front(), to_app_.size()))) {
    case PrefaceCheck::kComplete:
      stage_ = Stage::kReadyToServe;
      return;
    case PrefaceCheck::kNotHttp2:
      close("not an HTTP/2 client (no preface after the TLS handshake)");
      return;
    case PrefaceCheck::kSoFar:
      if (net_ended_) close("client closed before the HTTP/2 preface");
      return;
  }
}

bool TlsPump::read_net() {
  if (net_ended_) return false;
  const std::size_t space = to_app_.space();
  if (space == 0) {
    if (reading_waits_for_ != Want::kNothing) reading_waits_for_ = Want::kNothing;
    return false;
  }
  ERR_clear_error();
  errno = 0;
  const int n = SSL_read(ssl_, to_app_.back(), static_cast<int>(space));
  if (n > 0) {
    to_app_.appended(static_cast<std::size_t>(n));
    reading_waits_for_ = Want::kReadable;
    return true;
  }
  const int saved_errno = errno;
  const int error = SSL_get_error(ssl_, n);
  if (const auto wait = waits_for(error)) {
    reading_waits_for_ = *wait;
  } else if (error == SSL_ERROR_ZERO_RETURN || (error == SSL_ERROR_SYSCALL && saved_errno == 0)) {
    net_ended_ = true;  // close_notify, or the TCP stream's end
    reading_waits_for_ = Want::kNothing;
  } else {
    close(tls_failure(error, saved_errno));
  }
  return false;
}

bool TlsPump::write_app() {
  if (app_refuses_writes_) to_app_.taken(to_app_.size());  // nobody there to read it
  if (to_app_.empty()) return false;
  const ssize_t n = ::send(app_fd_, to_app_.front(), to_app_.size(), MSG_NOSIGNAL);
  if (n > 0) {
    to_app_.taken(static_cast<std::size_t>(n));
    return true;
  }
  if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) return false;
  // gRPC has closed its end: what it wrote before still goes to the client (read_app, write_net).
  app_refuses_writes_ = true;
  to_app_.taken(to_app_.size());
  return false;
}

bool TlsPump::read_app() {
  if (app_ended_) return false;
  const std::size_t space = to_net_.space();
  if (space == 0) return false;
  const ssize_t n = ::recv(app_fd_, to_net_.back(), space, 0);
  if (n > 0) {
    to_net_.appended(static_cast<std::size_t>(n));
    return true;
  }
  if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) return false;
  app_ended_ = true;  // gRPC closed its end (or it failed): send what it wrote, then end
  return false;
}

bool TlsPump::write_net() {
  if (to_net_.empty()) {
    writing_waits_for_ = Want::kNothing;
    return false;
  }
  ERR_clear_error();
  errno = 0;
  const int n = SSL_write(ssl_, to_net_.front(), static_cast<int>(to_net_.size()));
  if (n > 0) {
    to_net_.taken(static_cast<std::size_t>(n));
    writing_waits_for_ = Want::kNothing;
    return true;
  }
  const int saved_errno = errno;
  const int error = SSL_get_error(ssl_, n);
  if (const auto wait = waits_for(error)) {
    writing_waits_for_ = *wait;
  } else {
    close(tls_failure(error, saved_errno));
  }
  return false;
}

void TlsPump::pump() {
  // Until neither direction moves a byte: each step either moves some or says what it waits for.
  for (bool moved = true; moved && stage_ == Stage::kOpen;) {
    moved = false;
    moved |= read_net();
    if (stage_ != Stage::kOpen) return;
    moved |= write_app();
    if (stage_ != Stage::kOpen) return;
    moved |= read_app();
    moved |= write_net();
  }
  if (stage_ != Stage::kOpen) return;
  if (net_ended_ && to_app_.empty()) {
    close("client closed");
  } else if (app_ended_ && to_net_.empty()) {
    (void)SSL_shutdown(ssl_);  // close_notify, once, without waiting for the client's
    close("gRPC closed the connection");
  }
}

}  // namespace haptic::net
