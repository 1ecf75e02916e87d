// Bearer tokens and roles: the decision on one call's "authorization" metadata.
#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <sstream>

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
  EXPECT_EQ(late.error_message(), "authorization: token 'root' expired at 2023-11-14T22:13:20Z");
}

TEST(AccessControl, ARefusalNamesTheRoleNeededAndTheTokensRoleButNotTheCall) {
  // The client's error already begins with the call's name ("CreateObject: ...").
  const AccessControl access = make_access();
  const std::string header = "Bearer observer-secret-0001";
  const grpc::Status status =
      access.authorize_header(&header, Permission::kControl, "CreateObject", nullptr, system_clock::now());
  EXPECT_EQ(status.error_message(), "needs role CONTROLLER or above; token 'watcher' has role OBSERVER");
}

TEST(AccessControl, EveryRefusalIsLoggedWithThePeerTheTokenAndTheCallAtMostOnceASecond) {
  const AccessControl access = make_access();
  const AccessControl copy = access;  // the viewer's: one rate limit for both
  std::ostringstream log_text;
  auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(log_text);
  const auto previous = spdlog::default_logger();
  spdlog::set_default_logger(std::make_shared<spdlog::logger>("access-test", sink));
  const std::string observer = "Bearer observer-secret-0001";
  const std::string unknown = "Bearer not-a-token-at-all-000";
  const system_clock::time_point start = system_clock::from_time_t(1'800'000'000);
  (void)access.authorize_header(&observer, Permission::kAdmin, "KickSession", nullptr, start, "10.0.0.7");
  for (int i = 0; i < 50; ++i) {  // a guesser, within the same second: held back, counted
    (void)copy.authorize_header(&unknown, Permission::kObserve, "OpenSession", nullptr,
                                start + std::chrono::milliseconds(10 * i), "10.0.0.9");
  }
  (void)access.authorize_header(nullptr, Permission::kObserve, "OpenSession", nullptr,
                                start + std::chrono::milliseconds(1500), "10.0.0.9");
  spdlog::set_default_logger(previous);
  const std::string text = log_text.str();
  EXPECT_NE(text.find("access: KickSession refused from 10.0.0.7, token 'watcher': needs role ADMIN"),
            std::string::npos) << text;
  EXPECT_NE(text.find("access: OpenSession refused from 10.0.0.9, token none: authorization: this server "
                      "needs a bearer token"), std::string::npos) << text;
  EXPECT_NE(text.find("(50 more refused since the last line)"), std::string::npos) << text;
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 2) << text;
  EXPECT_EQ(access.refusals(), 52u);
  EXPECT_EQ(copy.refusals(), 52u);
}

}  // namespace
}  // namespace haptic::net
