#include "net/access_control.hpp"

#include <algorithm>
#include <ctime>
#include <string_view>

namespace haptic::net {
namespace {

v1::Role role_needed(Permission permission) {
  switch (permission) {
    case Permission::kObserve: return v1::OBSERVER;
    case Permission::kControl: return v1::CONTROLLER;
    case Permission::kAdmin: return v1::ADMIN;
  }
  return v1::ADMIN;
}

/// Compares every byte whatever the first difference, so the time taken does not tell a guesser
/// how much of a guess was right (nor, within the longer of the two, how long the token is).
bool same_secret(std::string_view offered, std::string_view known) {
  const std::size_t length = std::max(offered.size(), known.size());
  unsigned difference = offered.size() == known.size() ? 0U : 1U;
  for (std::size_t i = 0; i < length; ++i) {
    const unsigned char a = i < offered.size() ? static_cast<unsigned char>(offered[i]) : 0;
    const unsigned char b = i < known.size() ? static_cast<unsigned char>(known[i]) : 0;
    difference |= static_cast<unsigned>(a ^ b);
  }
  return difference == 0;
}

std::string utc_text(std::chrono::system_clock::time_point at) {
  const std::time_t seconds = std::chrono::system_clock::to_time_t(at);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

grpc::Status unauthenticated(const std::string& why) {
  return {grpc::StatusCode::UNAUTHENTICATED, std::string(kAuthorizationMetadataKey) + ": " + why};
}

}  // namespace

std::string role_name(v1::Role role) {
  switch (role) {
    case v1::OBSERVER: return "OBSERVER";
    case v1::CONTROLLER: return "CONTROLLER";
    case v1::ADMIN: return "ADMIN";
    default: return "no role";
  }
}

bool AccessControl::expired(const std::string& token_name,
                            std::chrono::system_clock::time_point now) const {
  for (const Credential& credential : credentials_) {
    if (credential.name == token_name) return credential.expires && now >= *credential.expires;
  }
  return false;
}

grpc::Status AccessControl::authorize(const grpc::ServerContext& context, Permission permission,
                                      const char* call, Caller* caller,
                                      std::chrono::system_clock::time_point now) const {
  if (!enabled()) return grpc::Status::OK;
  const auto& metadata = context.client_metadata();
  const auto found = metadata.find(kAuthorizationMetadataKey);
  if (found == metadata.end()) return authorize_header(nullptr, permission, call, caller, now);
  const std::string header(found->second.data(), found->second.size());
  return authorize_header(&header, permission, call, caller, now);
}

grpc::Status AccessControl::authorize_header(const std::string* header, Permission permission,
                                             const char* call, Caller* caller,
                                             std::chrono::system_clock::time_point now) const {
  if (!enabled()) return grpc::Status::OK;
  if (header == nullptr) {
    return unauthenticated(std::string(call) +
                           ": this server needs a bearer token with every call (metadata "
                           "\"authorization: Bearer <token>\"), and this call carries none");
  }
  constexpr std::string_view kScheme = "Bearer ";
  if (header->size() <= kScheme.size() || std::string_view(*header).substr(0, kScheme.size()) != kScheme) {
    return unauthenticated(std::string(call) + ": expected \"Bearer <token>\"");
  }
  const std::string_view offered = std::string_view(*header).substr(kScheme.size());
  const Credential* match = nullptr;
  for (const Credential& credential : credentials_) {  // all of them: the time tells nothing
    if (same_secret(offered, credential.token)) match = &credential;
  }
  if (match == nullptr) {
    return unauthenticated(std::string(call) + ": the token is not one this server knows");
  }
  if (match->expires && now >= *match->expires) {
    return unauthenticated(std::string(call) + ": token '" + match->name + "' expired at " +
                           utc_text(*match->expires));
  }
  const v1::Role needed = role_needed(permission);
  if (match->role < needed) {
    return {grpc::StatusCode::PERMISSION_DENIED,
            std::string(call) + " needs role " + role_name(needed) + " or above; token '" +
                match->name + "' has role " + role_name(match->role)};
  }
  if (caller != nullptr) *caller = {match->name, match->role};
  return grpc::Status::OK;
}

}  // namespace haptic::net
