#pragma once
// What the control plane's service needs of one call, whichever face carried it: gRPC
// (net/grpc_face) or the JSON face over HTTP and WebSocket. The service (net/haptic_service) sees
// only this, so access control, validation and every handler are written once for both.

#include <optional>
#include <string>
#include <string_view>

namespace haptic::net {

class CallContext {
 public:
  virtual ~CallContext() = default;
  /// The caller's host, in peer_host()'s form ("127.0.0.1", "[::1]"); "" when unknown.
  virtual std::string peer_host() const = 0;
  /// A value the call carries beside its request: gRPC metadata, or an HTTP request header.
  /// `key` is lower case ("authorization", "x-haptic-session-secret"); nullopt when not sent.
  virtual std::optional<std::string> metadata(std::string_view key) const = 0;
  /// True once the caller has gone (or the server is stopping): a streaming call then ends.
  virtual bool cancelled() const = 0;
};

/// A server-streaming call's messages out (WatchEvents): write() is false once the caller is gone.
template <typename Message>
class StreamWriter {
 public:
  virtual ~StreamWriter() = default;
  virtual bool write(const Message& message) = 0;
};

}  // namespace haptic::net
