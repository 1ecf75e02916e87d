#include "net/grpc_face.hpp"

#include <cstdlib>

#include "net/control_listener.hpp"
#include "net/session_registry.hpp"

namespace haptic::net {
namespace {

/// A gRPC call as the service sees it.
class GrpcCall final : public CallContext {
 public:
  explicit GrpcCall(grpc::ServerContext& context) : context_(context) {}

  /// Connections hapticd accepted itself (net::ControlListener) show as "fd:N" in gRPC's peer
  /// string: their address is the socket's own.
  std::string peer_host() const override {
    const std::string peer = context_.peer();
    if (peer.rfind("fd:", 0) == 0) {
      return ControlListener::host_of_connection(
          static_cast<int>(std::strtol(peer.c_str() + 3, nullptr, 10)));
    }
    return net::peer_host(peer);
  }

  /// gRPC's metadata, "-bin" values already decoded.
  std::optional<std::string> metadata(std::string_view key) const override {
    const auto& metadata = context_.client_metadata();
    const auto found = metadata.find(grpc::string_ref(key.data(), key.size()));
    if (found == metadata.end()) return std::nullopt;
    return std::string(found->second.data(), found->second.size());
  }

  bool cancelled() const override { return context_.IsCancelled(); }

 private:
  grpc::ServerContext& context_;
};

class GrpcEventWriter final : public StreamWriter<v1::Event> {
 public:
  explicit GrpcEventWriter(grpc::ServerWriter<v1::Event>& writer) : writer_(writer) {}
  bool write(const v1::Event& event) override { return writer_.Write(event); }

 private:
  grpc::ServerWriter<v1::Event>& writer_;
};

}  // namespace

#define HAPTIC_GRPC_UNARY(name, Request, Response)                                           \
  grpc::Status GrpcFace::name(grpc::ServerContext* context, const v1::Request* request,      \
                              v1::Response* response) {                                      \
    GrpcCall call(*context);                                                                 \
    return service_.name(&call, request, response);                                          \
  }
HAPTIC_V1_UNARY_RPCS(HAPTIC_GRPC_UNARY)
#undef HAPTIC_GRPC_UNARY

grpc::Status GrpcFace::WatchEvents(grpc::ServerContext* context,
                                   const v1::WatchEventsRequest* request,
                                   grpc::ServerWriter<v1::Event>* writer) {
  GrpcCall call(*context);
  GrpcEventWriter events(*writer);
  return service_.WatchEvents(&call, request, &events);
}

}  // namespace haptic::net
