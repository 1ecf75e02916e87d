#include "net/access_control.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <ctime>
#include <mutex>
#include <string_view>
#include <utility>

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

struct AccessControl::RefusalLog {
  std::mutex mutex;
  std::optional<std::int64_t> last_ns;  // the last line's time
  std::uint64_t held_back = 0;     // refusals since then, not written
  std::atomic<std::uint64_t> refusals{0};
};

AccessControl::AccessControl(std::vector<Credential> credentials)
    : credentials_(std::move(credentials)), log_(std::make_shared<RefusalLog>()) {}

std::uint64_t AccessControl::refusals() const { return log_->refusals.load(std::memory_order_relaxed); }

grpc::Status AccessControl::authorize(const CallContext& context, Permission permission,
                                      const char* call, Caller* caller, const std::string& peer,
                                      std::chrono::system_clock::time_point now) const {
  if (!enabled()) return grpc::Status::OK;
  const std::optional<std::string> header = context.metadata(kAuthorizationMetadataKey);
  return authorize_header(header ? &*header : nullptr, permission, call, caller, now, peer);
}

grpc::Status AccessControl::authorize_header(const std::string* header, Permission permission,
                                             const char* call, Caller* caller,
                                             std::chrono::system_clock::time_point now,
                                             const std::string& peer) const {
  if (!enabled()) return grpc::Status::OK;
  std::string holder;
  grpc::Status status = decide(header, permission, caller, now, holder);
  if (!status.ok()) log_refusal(peer, holder, call, status, now);
  return status;
}

void AccessControl::log_refusal(const std::string& peer, const std::string& holder, const char* call,
                                const grpc::Status& status, std::chrono::system_clock::time_point now) const {
  log_->refusals.fetch_add(1, std::memory_order_relaxed);
  const std::int64_t now_ns =
      std::chrono::duration_cast<std::chrono::nanoseconds>(now.time_since_epoch()).count();
  std::uint64_t held_back = 0;
  {
    std::lock_guard lock(log_->mutex);
    // At most one line a second, so that a guesser's flood cannot flood the log (a clock set
    // back starts a new second at once).
    if (log_->last_ns && now_ns >= *log_->last_ns && now_ns - *log_->last_ns < 1'000'000'000) {
      ++log_->held_back;
      return;
    }
    log_->last_ns = now_ns;
    held_back = std::exchange(log_->held_back, 0);
  }
  spdlog::warn("access: {} refused from {}, token {}: {}{}", call, peer.empty() ? "?" : peer, holder,
               status.error_message(),
               held_back == 0 ? std::string() : " (" + std::to_string(held_back) + " more refused since the last line)");
}

grpc::Status AccessControl::decide(const std::string* header, Permission permission, Caller* caller,
                                   std::chrono::system_clock::time_point now,
                                   std::string& holder) const {
  holder = "none";
  if (header == nullptr) {
    return unauthenticated("this server needs a bearer token with every call (metadata "
                           "\"authorization: Bearer <token>\"), and this call carries none");
  }
  constexpr std::string_view kScheme = "Bearer ";
  if (header->size() <= kScheme.size() || std::string_view(*header).substr(0, kScheme.size()) != kScheme) {
    holder = "malformed";
    return unauthenticated("expected \"Bearer <token>\"");
  }
  const std::string_view offered = std::string_view(*header).substr(kScheme.size());
  const Credential* match = nullptr;
  for (const Credential& credential : credentials_) {  // all of them: the time tells nothing
    if (same_secret(offered, credential.token)) match = &credential;
  }
  if (match == nullptr) {
    holder = "unknown";
    return unauthenticated("the token is not one this server knows");
  }
  holder = "'" + match->name + "'";
  if (match->expires && now >= *match->expires) {
    return unauthenticated("token '" + match->name + "' expired at " + utc_text(*match->expires));
  }
  const v1::Role needed = role_needed(permission);
  if (match->role < needed) {
    return {grpc::StatusCode::PERMISSION_DENIED,
            "needs role " + role_name(needed) + " or above; token '" + match->name + "' has role " +
                role_name(match->role)};
  }
  if (caller != nullptr) *caller = {match->name, match->role};
  return grpc::Status::OK;
}

}  // namespace haptic::net
