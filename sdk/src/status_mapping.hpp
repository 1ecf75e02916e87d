#pragma once
// grpc::Status -> the SDK's exception types.

#include <grpcpp/support/status.h>

#include <string>

namespace haptic::detail {

/// Throws the haptic::Error subclass for a failed status; returns if it is OK. `call` names the
/// RPC for the message ("CreateObject: object.impedance.stiffness: must be ...").
void throw_if_failed(const grpc::Status& status, const std::string& call);

}  // namespace haptic::detail
