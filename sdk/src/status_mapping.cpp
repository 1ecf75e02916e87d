#include "status_mapping.hpp"

#include <cstdlib>

#include "haptic/client.hpp"
#include "haptic/error.hpp"

namespace haptic::detail {
namespace {

// The server says "api_version: client speaks X, server speaks Y"; pick Y out if it is there.
std::uint32_t server_version_in(const std::string& message) {
  const std::string marker = "server speaks ";
  const auto at = message.find(marker);
  if (at == std::string::npos) return 0;
  return static_cast<std::uint32_t>(std::strtoul(message.c_str() + at + marker.size(), nullptr, 10));
}

}  // namespace

void throw_if_failed(const grpc::Status& status, const std::string& call) {
  if (status.ok()) return;
  const std::string message = call + ": " + status.error_message();
  switch (status.error_code()) {
    case grpc::StatusCode::UNAVAILABLE:
    case grpc::StatusCode::DEADLINE_EXCEEDED:
    case grpc::StatusCode::CANCELLED:
      throw ConnectionError(message);
    case grpc::StatusCode::INVALID_ARGUMENT:
    case grpc::StatusCode::OUT_OF_RANGE:
      throw InvalidArgumentError(message);
    case grpc::StatusCode::NOT_FOUND:
      throw NotFoundError(message);
    case grpc::StatusCode::PERMISSION_DENIED:
      throw PermissionDeniedError(message);
    case grpc::StatusCode::UNAUTHENTICATED:
      throw UnauthenticatedError(message);
    case grpc::StatusCode::RESOURCE_EXHAUSTED:
      throw ResourceExhaustedError(message);
    case grpc::StatusCode::FAILED_PRECONDITION:
      if (status.error_message().rfind("api_version:", 0) == 0) {
        throw VersionMismatchError(message, kApiVersion, server_version_in(status.error_message()));
      }
      throw FailedPreconditionError(message);
    default:
      throw Error(ErrorCode::kInternal, message);
  }
}

}  // namespace haptic::detail
