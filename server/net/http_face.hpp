#pragma once
// The control plane over HTTP (http_address; docs/http.md): net::JsonFace on an HttpServer of its
// own. What the HTTP side adds, and nothing else:
//   - the call's context: the peer's host, the headers as the call's metadata ("-bin" headers
//     base64-decoded, as gRPC does: haptic-session-secret-bin), so access control and the
//     session's secret are checked by the service as over gRPC;
//   - the body's form from its Content-Type (application/json, application/proto; 415 else);
//   - browsers: a request carrying an Origin header is served only when that origin is in
//     http_allowed_origins (403 else, before the service sees it), with CORS headers naming it,
//     and a CORS preflight (OPTIONS) answered for those origins alone. No secret rides in a URL:
//     the token and the session secret are headers.
//   - the streams, as WebSockets at /haptic.v1.Haptic/WatchEvents (each Event a text message,
//     {"event": {...}}) and /haptic.v1.Haptic/StreamState (each sample a binary message, the UDP
//     State datagram byte for byte). A browser cannot set headers on a WebSocket, so the client's
//     first message opens the stream: {"request": {...}, "authorization": "Bearer …",
//     "session_secret": "<base64>"} (the last two may be headers of the upgrade instead). A
//     refusal is a last text message {"error": {"code": …, "message": …}} and a close (1008).

#include <cstdint>
#include <string>
#include <vector>

#include <optional>

#include "net/http_server.hpp"
#include "net/json_face.hpp"

namespace haptic::net {

struct HttpFaceOptions {
  /// Origins ("https://lab.example:8443") whose pages may call the face; none: no browser page
  /// may (a request without an Origin header, any non-browser client, is served).
  std::vector<std::string> allowed_origins;
  HttpLimits limits = default_limits();

  /// A control plane's limits: bodies up to 4 MiB (gRPC's default message size), POST for calls,
  /// OPTIONS for a browser's preflight, GET for the index; eight calls handled at once.
  static HttpLimits default_limits() {
    HttpLimits limits;
    limits.max_body_bytes = 4u << 20;
    limits.methods = {"POST", "OPTIONS", "GET", "HEAD"};
    limits.handler_threads = 8;
    limits.max_connections = 64;
    limits.max_connections_per_peer = 16;
    return limits;
  }
};

class HttpFace {
 public:
  HttpFace(HapticService& service, HttpFaceOptions options);

  /// Listens on "host:port" (port 0 picks one). Throws std::runtime_error naming http_address.
  void bind(const std::string& address) { http_.bind(address, "http_address"); }
  std::uint16_t port() const { return http_.port(); }
  /// HTTPS only, with this context (ALPN "http/1.1"; with a client CA, mutual TLS). Before start().
  void use_tls(std::shared_ptr<const TlsServerContext> tls) { http_.use_tls(std::move(tls)); }
  void start();
  void stop() { http_.stop(); }

  /// One request's reply (on a handler thread of the server).
  HttpResponse handle(const HttpRequest& request) const;
  /// A WebSocket upgrade: nullopt accepts it, else the refusal (an origin not allowed, no such
  /// stream).
  std::optional<HttpResponse> check_upgrade(const HttpRequest& request) const;
  /// A stream's life on its WebSocket.
  void stream(const HttpRequest& request, WebSocketChannel& channel) const;

  const HttpServer& server() const { return http_; }

 private:
  /// The refusal of a browser's request from an origin not in allowed_origins; nullopt for an
  /// allowed one, or a request without an Origin (a client that is no browser).
  std::optional<HttpResponse> origin_refusal(const HttpRequest& request) const;

  HapticService& service_;
  JsonFace face_;
  HttpFaceOptions options_;
  HttpServer http_;
};

/// A stream's opening message, read: the request as JSON, the credentials it carries; or why it
/// is refused.
struct StreamOpening {
  std::string request;                        // the "request" object, as JSON
  std::optional<std::string> authorization;   // "Bearer …"
  std::optional<std::string> session_secret;  // decoded
  std::string error;                          // "" when it reads
};
StreamOpening read_opening(const std::string& message);

/// Encodes base64 (the standard alphabet, padded), as gRPC's "-bin" metadata and protobuf's JSON
/// mapping write bytes.
std::string encode_base64(std::string_view bytes);

/// Decodes base64 (standard or URL-safe alphabet, padding optional, as gRPC's "-bin" metadata
/// takes it); false when `text` is not base64.
bool decode_base64(std::string_view text, std::string& out);

}  // namespace haptic::net
