#pragma once
// One TLS connection of the control plane, from the TCP socket to gRPC: the handshake, the
// HTTP/2 client preface read through it (so a connection that never speaks HTTP/2 is never handed
// to gRPC), then bytes copied both ways between the TLS socket ("net") and the local end of a
// socket pair whose other end gRPC serves in plaintext ("app"). Everything non-blocking: the
// control listener's epoll calls advance() whenever either socket is ready, and asks interest()
// what to wait for next. Bounded: at most kQueueBytes queued in each direction (a side that does
// not read stops the other from being read).

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

struct ssl_st;

namespace haptic::net {

/// What the first bytes of a connection say about the HTTP/2 client preface (RFC 9113 §3.4):
/// the whole preface, a beginning of it so far, or something else.
enum class PrefaceCheck { kComplete, kSoFar, kNotHttp2 };
PrefaceCheck check_http2_preface(std::string_view first_bytes);
/// Its length: "PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n".
inline constexpr std::size_t kHttp2PrefaceBytes = 24;

class TlsPump {
 public:
  enum class Stage {
    kHandshake,     // TLS handshake in progress
    kPreface,       // handshake done; the HTTP/2 preface not yet all read
    kReadyToServe,  // preface read: attach_app() the socket pair's end, then kOpen
    kOpen,          // copying both ways
    kClosed,        // ended: why() says why; close everything
  };
  struct Interest {
    bool net_read = false, net_write = false, app_read = false, app_write = false;
    bool operator==(const Interest&) const = default;
  };
  /// Bytes queued at most in each direction.
  static constexpr std::size_t kQueueBytes = 64 * 1024;

  /// Takes `ssl` (server side, attached to the non-blocking socket `net_fd`); owns both from here.
  TlsPump(ssl_st* ssl, int net_fd);
  ~TlsPump();
  TlsPump(const TlsPump&) = delete;
  TlsPump& operator=(const TlsPump&) = delete;

  /// Does all the work the sockets allow now; returns the stage it ends in.
  Stage advance();
  /// In kReadyToServe: the local end (non-blocking, owned from here) of the socket pair whose
  /// other end gRPC now serves. Moves to kOpen and hands it the preface and what followed.
  void attach_app(int app_fd);

  Stage stage() const { return stage_; }
  Interest interest() const;
  int net_fd() const { return net_fd_; }
  int app_fd() const { return app_fd_; }
  /// Why the connection ended (for the log): "client closed", "TLS: certificate verify failed"…
  const std::string& why() const { return why_; }
  /// The handshake had completed (an ending after it is not a refused handshake).
  bool handshake_done() const { return handshake_completed_; }

 private:
  /// A byte queue of kQueueBytes: appended at the back, taken from the front.
  /// Its memory is taken on first use: a connection that never completes its handshake holds
  /// none.
  class Queue {
   public:
    char* back() { compact(); return bytes_.get() + end_; }
    std::size_t space() { compact(); return kQueueBytes - end_; }
    void appended(std::size_t n) { end_ += n; }
    const char* front() const { return bytes_.get() + begin_; }
    std::size_t size() const { return end_ - begin_; }
    bool empty() const { return begin_ == end_; }
    void taken(std::size_t n) { begin_ += n; if (begin_ == end_) begin_ = end_ = 0; }

   private:
    void compact();
    std::unique_ptr<char[]> bytes_;
    std::size_t begin_ = 0, end_ = 0;
  };

  void handshake();
  void read_preface();
  void pump();
  /// SSL_read into to_app_; false when nothing more can be read now (or the stream ended).
  bool read_net();
  bool write_app();
  bool read_app();
  bool write_net();
  void close(std::string why);

  ssl_st* ssl_;
  int net_fd_;
  int app_fd_ = -1;
  Stage stage_ = Stage::kHandshake;
  bool handshake_completed_ = false;
  Queue to_app_;  // decrypted, for gRPC
  Queue to_net_;  // from gRPC, to encrypt
  bool net_ended_ = false;   // the client closed (close_notify or EOF)
  bool app_ended_ = false;   // gRPC closed its end: everything it wrote has been read
  bool app_refuses_writes_ = false;  // gRPC's end is closed: bytes for it are dropped
  /// What the last TLS read (the handshake's steps included) and the last TLS write wait for
  /// on the network socket: either may need the other direction (TLS 1.3 key updates).
  enum class Want { kNothing, kReadable, kWritable };
  /// What a TLS call that failed with `ssl_error` (SSL_get_error) waits for on the socket;
  /// nullopt when it is not waiting but ended or failed.
  static std::optional<Want> waits_for(int ssl_error);
  Want reading_waits_for_ = Want::kReadable;
  Want writing_waits_for_ = Want::kNothing;
  std::string why_;
};

}  // namespace haptic::net
