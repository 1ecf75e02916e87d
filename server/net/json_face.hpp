#pragma once
// haptic.v1.Haptic over plain HTTP (docs/http.md): the Connect protocol's unary form. A call is
// `POST /haptic.v1.Haptic/<Method>` with the request as the body, in protobuf's JSON mapping
// (Content-Type application/json) or its binary form (application/proto); the reply is the
// response in the same form, or an error as JSON, {"code": "invalid_argument", "message": "…"},
// under the HTTP status Connect gives that code. The token and the session secret travel as
// headers, as over gRPC: "authorization: Bearer …" and "haptic-session-secret-bin: <base64>".
//
// Nothing is decided here but the encoding: each call goes to the same HapticService handler as
// over gRPC, with the same access control and validation (net/haptic_service).

#include <grpcpp/support/status.h>

#include <google/protobuf/descriptor.h>

#include <string>
#include <string_view>
#include <vector>

#include "net/call_context.hpp"
#include "net/haptic_service.hpp"

namespace haptic::net {

/// How a body is written.
enum class BodyCodec {
  kJson,   // application/json: protobuf's JSON mapping
  kProto,  // application/proto: protobuf's binary form
};

/// One call's reply, for the HTTP server to send.
struct FaceReply {
  grpc::StatusCode code = grpc::StatusCode::OK;
  int http_status = 200;
  std::string content_type;
  std::string body;
};

/// One call of the face: its name and its request's and response's types.
struct FaceMethod {
  std::string_view name;
  const google::protobuf::Descriptor* request;
  const google::protobuf::Descriptor* response;
};

class JsonFace {
 public:
  /// The path prefix of every call: "/haptic.v1.Haptic/".
  static constexpr std::string_view kPathPrefix = "/haptic.v1.Haptic/";

  explicit JsonFace(HapticService& service) : service_(service) {}

  /// Runs `method` ("CreateObject") on `body`. A method the service lacks is UNIMPLEMENTED naming
  /// it (a stream, WatchEvents, says to open it as a WebSocket); a body that does not parse is
  /// INVALID_ARGUMENT naming what is wrong, before the service sees anything. Never throws: a
  /// handler's exception is INTERNAL.
  FaceReply call(std::string_view method, std::string_view body, BodyCodec codec,
                 CallContext& context) const;

  /// Every unary call the face serves, in service.proto's order.
  static std::vector<FaceMethod> methods();

 private:
  HapticService& service_;
};

/// A status as the face writes it: Connect's HTTP status for its code, and the JSON error body.
FaceReply error_reply(const grpc::Status& status);

/// Connect's name of a gRPC code: "invalid_argument", "canceled", …
std::string_view code_name(grpc::StatusCode code);

/// The HTTP status Connect gives a code (connectrpc.com/docs/protocol, "Error codes"): 400 for
/// invalid_argument, failed_precondition and out_of_range, 401 unauthenticated, 403
/// permission_denied, 404 not_found, 409 already_exists and aborted, 429 resource_exhausted, 499
/// canceled, 501 unimplemented, 503 unavailable, 504 deadline_exceeded, 500 otherwise.
int http_status_of(grpc::StatusCode code);

}  // namespace haptic::net
