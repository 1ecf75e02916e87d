#pragma once
// Bearer tokens with roles (docs/deployment.md). Without tokens every caller may do everything
// (loopback, lockstep, CI). With tokens, every call carries one as metadata
// "authorization: Bearer <token>", and each RPC needs a role: OBSERVER < CONTROLLER < ADMIN, each
// including the ones before it.

#include <grpcpp/support/status.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "haptic/v1/types.pb.h"
#include "net/call_context.hpp"

namespace haptic::net {

inline constexpr const char* kAuthorizationMetadataKey = "authorization";

/// What a call asks to do; each RPC names one (haptic_service.cpp).
enum class Permission {
  kObserve,  // OBSERVER: sessions, state, events, reading the device and the scene
  kControl,  // CONTROLLER: changing the scene, the simulated operator, lockstep steps
  kAdmin,    // ADMIN: statistics, every session, ending one
};

/// One configured token.
struct Credential {
  std::string name;   // who holds it: shown in logs, events and ListSessions
  std::string token;  // the secret
  v1::Role role = v1::ROLE_UNSPECIFIED;
  std::optional<std::chrono::system_clock::time_point> expires;  // none: never
};

/// Who made a call: the token's holder and role; empty and ROLE_UNSPECIFIED without tokens.
struct Caller {
  std::string token_name;
  v1::Role role = v1::ROLE_UNSPECIFIED;
};

class AccessControl {
 public:
  /// No tokens: every call is allowed.
  explicit AccessControl(std::vector<Credential> credentials = {});

  bool enabled() const { return !credentials_.empty(); }

  /// OK (and *caller filled in) when the call may do `permission`. UNAUTHENTICATED when the call
  /// carries no token, a malformed one, an unknown one or an expired one; PERMISSION_DENIED when
  /// its role does not allow `call` (the RPC's name). Each message names what was wrong, not the
  /// call (the caller's own error says which call it made). Every refusal is logged with `peer`
  /// (the caller's host), the token's name ("none", "an unknown token") and `call`: at most one
  /// line a second, with the number held back.
  grpc::Status authorize(const CallContext& context, Permission permission,
                         const char* call, Caller* caller, const std::string& peer,
                         std::chrono::system_clock::time_point now =
                             std::chrono::system_clock::now()) const;

  /// True when the token named `token_name` has an expiry at or before `now`.
  bool expired(const std::string& token_name, std::chrono::system_clock::time_point now) const;

  /// The same decision over the header's value alone (nullptr: none sent): the web viewer's.
  grpc::Status authorize_header(const std::string* header, Permission permission, const char* call,
                                Caller* caller, std::chrono::system_clock::time_point now,
                                const std::string& peer = {}) const;

  /// Refusals so far (each logged or held back).
  std::uint64_t refusals() const;

 private:
  /// The decision; `holder` says whose token it was, for the log.
  grpc::Status decide(const std::string* header, Permission permission, Caller* caller,
                      std::chrono::system_clock::time_point now, std::string& holder) const;
  void log_refusal(const std::string& peer, const std::string& holder, const char* call,
                   const grpc::Status& status, std::chrono::system_clock::time_point now) const;

  std::vector<Credential> credentials_;
  /// The refusal log's rate limit, shared by every copy of this object (the service's and the
  /// viewer's are copies).
  struct RefusalLog;
  std::shared_ptr<RefusalLog> log_;
};

/// "OBSERVER", "CONTROLLER", "ADMIN".
std::string role_name(v1::Role role);

}  // namespace haptic::net
