#pragma once
// The SDK's exceptions: one small hierarchy, each carrying the server's message.
//
// Every message reads "<call>: <field path>: <what is wrong>" (the path where there is one):
// <call> is the RPC the failing method makes (CreateObject, UpdateObject, ApplyScene,
// SetOperator, GetStats, ...), or the method's own name for one that makes none (session_id,
// poll_state), or "ClientConfig" for a bad configuration; <field path> is the server's name for
// the field ("object.sphere.radius", "scene.objects[2].impedance.stiffness", "input.target.x").
// A mistake the SDK catches before asking reads exactly as the server would say it.

#include <cstdint>
#include <stdexcept>
#include <string>

namespace haptic {

enum class ErrorCode {
  kConnection,          ///< server unreachable or too slow (UNAVAILABLE, DEADLINE_EXCEEDED)
  kInvalidArgument,     ///< a field was wrong; the message names it
  kNotFound,            ///< no such session or item (a lost lease shows up here)
  kPermissionDenied,    ///< the item belongs to another client, or the token's role forbids it
  kResourceExhausted,   ///< a server limit (sessions, objects per session)
  kFailedPrecondition,  ///< not possible in the server's state (e.g. Step in real time)
  kVersionMismatch,     ///< client and server speak different API versions
  kInternal,            ///< anything else
  kUnauthenticated,     ///< no token, or one the server does not know or that has expired
};

class Error : public std::runtime_error {
 public:
  Error(ErrorCode code, const std::string& message) : std::runtime_error(message), code_(code) {}
  ErrorCode code() const noexcept { return code_; }

 private:
  ErrorCode code_;
};

class ConnectionError : public Error {
 public:
  explicit ConnectionError(const std::string& m) : Error(ErrorCode::kConnection, m) {}
};
class InvalidArgumentError : public Error {
 public:
  explicit InvalidArgumentError(const std::string& m) : Error(ErrorCode::kInvalidArgument, m) {}
};
class NotFoundError : public Error {
 public:
  explicit NotFoundError(const std::string& m) : Error(ErrorCode::kNotFound, m) {}
};
class PermissionDeniedError : public Error {
 public:
  explicit PermissionDeniedError(const std::string& m) : Error(ErrorCode::kPermissionDenied, m) {}
};
class UnauthenticatedError : public Error {
 public:
  explicit UnauthenticatedError(const std::string& m) : Error(ErrorCode::kUnauthenticated, m) {}
};
class ResourceExhaustedError : public Error {
 public:
  explicit ResourceExhaustedError(const std::string& m) : Error(ErrorCode::kResourceExhausted, m) {}
};
class FailedPreconditionError : public Error {
 public:
  explicit FailedPreconditionError(const std::string& m) : Error(ErrorCode::kFailedPrecondition, m) {}
};
class VersionMismatchError : public Error {
 public:
  VersionMismatchError(const std::string& m, std::uint32_t client_version, std::uint32_t server_version)
      : Error(ErrorCode::kVersionMismatch, m),
        client_version_(client_version),
        server_version_(server_version) {}
  std::uint32_t client_version() const noexcept { return client_version_; }
  std::uint32_t server_version() const noexcept { return server_version_; }

 private:
  std::uint32_t client_version_;
  std::uint32_t server_version_;
};

}  // namespace haptic
