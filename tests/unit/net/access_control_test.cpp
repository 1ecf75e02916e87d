// Bearer tokens and roles: the decision on one call's "authorization" metadata.
#include <gtest/gtest.h>

#include "net/access_control.hpp"

namespace haptic::net {
namespace {

using std::chrono::system_clock;

AccessControl make_access() {
  const system_clock::time_point expiry = system_clock::from_time_t(1'700'000'000);  // 2023-11-14
  return AccessControl({{"watcher", "observer-secret-0001", v1::OBSERVER, std::nullopt},
                        {"operator", "controller-secret-01", v1::CONTROLLER, std::nullopt},
                        {"root", "admin-secret-0000001", v1::ADMIN, expiry}});
}

grpc::StatusCode code_of(const AccessControl& access, const char* header, Permission permission,
                         system_clock::time_point now, Caller* caller = nullptr) {
  const std::string value = header == nullptr ? "" : header;
  return access.authorize_header(header == nullptr ? nullptr : &value, permission, "Call", caller, now)
      .error_code();
}

TEST(AccessControl, WithoutTokensEveryCallIsAllowed) {
  const AccessControl open;
  EXPECT_FALSE(open.enabled());
  EXPECT_TRUE(open.authorize_header(nullptr, Permission::kAdmin, "GetStats", nullptr, system_clock::now()).ok());
}

TEST(AccessControl, EachRoleIncludesTheOnesBelowIt) {
  const AccessControl access = make_access();
  const system_clock::time_point before_expiry = system_clock::from_time_t(1'600'000'000);
  using enum Permission;
  const struct {
    const char* header;
    Permission permission;
    grpc::StatusCode expected;
  } cases[] = {
      {"Bearer observer-secret-0001", kObserve, grpc::StatusCode::OK},
      {"Bearer observer-secret-0001", kControl, grpc::StatusCode::PERMISSION_DENIED},
      {"Bearer observer-secret-0001", kAdmin, grpc::StatusCode::PERMISSION_DENIED},
      {"Bearer controller-secret-01", kObserve, grpc::StatusCode::OK},
      {"Bearer controller-secret-01", kControl, grpc::StatusCode::OK},
      {"Bearer controller-secret-01", kAdmin, grpc::StatusCode::PERMISSION_DENIED},
      {"Bearer admin-secret-0000001", kAdmin, grpc::StatusCode::OK},
      {"Bearer admin-secret-0000001", kObserve, grpc::StatusCode::OK},
      {nullptr, kObserve, grpc::StatusCode::UNAUTHENTICATED},
      {"observer-secret-0001", kObserve, grpc::StatusCode::UNAUTHENTICATED},       // no scheme
      {"Bearer observer-secret-000", kObserve, grpc::StatusCode::UNAUTHENTICATED},  // a prefix
      {"Bearer observer-secret-00012", kObserve, grpc::StatusCode::UNAUTHENTICATED},
      {"Bearer ", kObserve, grpc::StatusCode::UNAUTHENTICATED},
  };
  for (const auto& c : cases) {
    EXPECT_EQ(code_of(access, c.header, c.permission, before_expiry), c.expected)
        << (c.header ? c.header : "(none)") << " for permission " << static_cast<int>(c.permission);
  }
}

TEST(AccessControl, AnExpiredTokenIsUnauthenticatedFromItsExpiryOn) {
  const AccessControl access = make_access();
  const system_clock::time_point expiry = system_clock::from_time_t(1'700'000'000);
  Caller caller;
  EXPECT_EQ(code_of(access, "Bearer admin-secret-0000001", Permission::kAdmin,
                    expiry - std::chrono::seconds(1), &caller),
            grpc::StatusCode::OK);
  EXPECT_EQ(caller.token_name, "root");
  EXPECT_EQ(caller.role, v1::ADMIN);
  const std::string header = "Bearer admin-secret-0000001";
  const grpc::Status late = access.authorize_header(&header, Permission::kObserve, "GetStats", nullptr, expiry);
  EXPECT_EQ(late.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(late.error_message(), "authorization: GetStats: token 'root' expired at 2023-11-14T22:13:20Z");
}

TEST(AccessControl, ARefusalNamesTheCallTheRoleNeededAndTheTokensRole) {
  const AccessControl access = make_access();
  const std::string header = "Bearer observer-secret-0001";
  const grpc::Status status =
      access.authorize_header(&header, Permission::kControl, "CreateObject", nullptr, system_clock::now());
  EXPECT_EQ(status.error_message(),
            "CreateObject needs role CONTROLLER or above; token 'watcher' has role OBSERVER");
}

}  // namespace
}  // namespace haptic::net
