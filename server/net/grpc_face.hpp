#pragma once
// haptic.v1.Haptic over gRPC: each call handed to the one HapticService with its context as a
// CallContext (the peer's host, its metadata, whether it was cancelled). Nothing else is decided
// here, so the gRPC face and the JSON face cannot differ.

#include "haptic/v1/service.grpc.pb.h"
#include "net/haptic_service.hpp"

namespace haptic::net {

class GrpcFace final : public v1::Haptic::Service {
 public:
  explicit GrpcFace(HapticService& service) : service_(service) {}

#define HAPTIC_GRPC_UNARY(name, Request, Response)                                           \
  grpc::Status name(grpc::ServerContext* context, const v1::Request* request,                \
                    v1::Response* response) override;
  HAPTIC_V1_UNARY_RPCS(HAPTIC_GRPC_UNARY)
#undef HAPTIC_GRPC_UNARY
  grpc::Status WatchEvents(grpc::ServerContext* context, const v1::WatchEventsRequest* request,
                           grpc::ServerWriter<v1::Event>* writer) override;

 private:
  HapticService& service_;
};

}  // namespace haptic::net
