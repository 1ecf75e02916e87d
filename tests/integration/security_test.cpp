// The control plane's security end to end (issue 11 item 1): TLS from the configuration, optional
// mutual TLS, bearer tokens with roles. Every refusal carries the right gRPC code (as the SDK's
// error class) and a message naming what was wrong, and no refused call changes anything.

#include <gtest/gtest.h>

#include <condition_variable>
#include <ctime>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "haptic/client.hpp"
#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"

namespace haptic::test {
namespace {

const std::string kCerts = TEST_CERTS_DIR;
constexpr const char* kObserverToken = "observer-token-0123456789";
constexpr const char* kControllerToken = "controller-token-0123456789";
constexpr const char* kAdminToken = "admin-token-0123456789abcdef";
constexpr const char* kExpiredToken = "expired-token-0123456789abc";

std::string tokens_json() {
  return R"("tokens": [
      {"name": "watcher", "token": ")" + std::string(kObserverToken) + R"(", "role": "OBSERVER"},
      {"name": "operator", "token": ")" + std::string(kControllerToken) + R"(", "role": "CONTROLLER"},
      {"name": "root", "token": ")" + std::string(kAdminToken) + R"(", "role": "ADMIN"},
      {"name": "former", "token": ")" + std::string(kExpiredToken) +
         R"(", "role": "CONTROLLER", "expires": "2020-01-01T00:00:00Z"}])";
}

/// A lockstep server with TLS and the four tokens above; `client_ca` adds mutual TLS.
std::string secured_config(bool client_ca = false) {
  std::string tls = R"("tls": {"cert_file": ")" + kCerts + R"(/server.pem", "key_file": ")" +
                    kCerts + "/server.key\"";
  if (client_ca) tls += R"(, "client_ca_file": ")" + kCerts + "/ca.pem\"";
  return R"({"time_mode": "LOCKSTEP", "security": {)" + tls + "}, " + tokens_json() + "}}";
}

ClientConfig tls_client(const ServerProcess& server, const char* name, const char* token,
                        const std::string& ca = kCerts + "/ca.pem") {
  ClientConfig config = config_for(server, name);
  config.tls = TlsOptions{};
  config.tls->ca_file = ca;
  if (token != nullptr) config.token = token;
  config.rpc_timeout = std::chrono::milliseconds(3000);
  return config;
}

/// Runs `body`, which must throw an `ErrorType`; returns its message.
template <typename ErrorType, typename Body>
std::string refusal(Body&& body) {
  try {
    body();
  } catch (const ErrorType& error) {
    return error.what();
  } catch (const std::exception& error) {
    ADD_FAILURE() << "wrong error: " << error.what();
    return {};
  }
  ADD_FAILURE() << "no error";
  return {};
}

TEST(Security, TheRightTokenOverTlsOpensASessionThatWorks) {
  ServerProcess server(secured_config());
  Client controller(tls_client(server, "controller", kControllerToken));
  ObjectHandle wall = controller.add_wall({.normal = {0, 0, 1}, .impedance = {800.0, 1.0}});
  EXPECT_GT(wall.id(), 0u);
  EXPECT_EQ(controller.step(10), 10u);  // ticks count from 1
}

TEST(Security, MissingWrongAndExpiredTokensAreUnauthenticated) {
  ServerProcess server(secured_config());
  const std::string none =
      refusal<UnauthenticatedError>([&] { Client client(tls_client(server, "no-token", nullptr)); });
  // One call name per error: the SDK's, in front.
  EXPECT_EQ(none.rfind("OpenSession: authorization: this server needs a bearer token", 0), 0u) << none;
  EXPECT_EQ(none.find("OpenSession", 1), std::string::npos) << none;
  const std::string wrong = refusal<UnauthenticatedError>(
      [&] { Client client(tls_client(server, "wrong", "not-a-token-anyone-was-given")); });
  EXPECT_NE(wrong.find("the token is not one this server knows"), std::string::npos) << wrong;
  const std::string expired =
      refusal<UnauthenticatedError>([&] { Client client(tls_client(server, "late", kExpiredToken)); });
  EXPECT_NE(expired.find("token 'former' expired at 2020-01-01T00:00:00Z"), std::string::npos)
      << expired;
}

TEST(Security, AnObserverWatchesButCannotChangeAnything) {
  ServerProcess server(secured_config());
  Client admin(tls_client(server, "admin", kAdminToken));
  Client controller(tls_client(server, "controller", kControllerToken));
  ObjectHandle wall = controller.add_wall({.normal = {0, 0, 1}, .impedance = {800.0, 1.0}});
  Client observer(tls_client(server, "observer", kObserverToken));  // subscribes to state: allowed

  const std::string create = refusal<PermissionDeniedError>(
      [&] { (void)observer.add_wall({.normal = {1, 0, 0}, .impedance = {500.0, 1.0}}); });
  EXPECT_NE(create.find("CreateObject: needs role CONTROLLER or above; token 'watcher' has role OBSERVER"),
            std::string::npos) << create;
  refusal<PermissionDeniedError>([&] { (void)observer.apply_scene(SceneSpec{}); });
  refusal<PermissionDeniedError>([&] { (void)observer.step(1); });
  refusal<PermissionDeniedError>([&] { observer.set_operator({}); });
  refusal<PermissionDeniedError>([&] { (void)observer.stats(); });
  refusal<PermissionDeniedError>([&] { (void)controller.stats(); });
  refusal<PermissionDeniedError>([&] { (void)controller.sessions(); });
  const std::string kick = refusal<PermissionDeniedError>(
      [&] { controller.kick_session(observer.session_id()); });
  EXPECT_NE(kick.find("KickSession: needs role ADMIN"), std::string::npos) << kick;

  // Reading is allowed, and state reaches the observer once the controller steps.
  EXPECT_NO_THROW((void)observer.scene_energy());
  EXPECT_NO_THROW((void)observer.scene(true));  // reading the scene is observing it
  const std::uint64_t tick = controller.step(5);
  State state;
  EXPECT_TRUE(observer.wait_for_tick(tick, state, std::chrono::seconds(5)));

  // 0 cross-session changes: the scene holds the controller's one wall, nothing else.
  const Stats stats = admin.stats();
  EXPECT_EQ(stats.objects, 1u);
  EXPECT_EQ(stats.fields, 0u);
  EXPECT_EQ(stats.sessions, 3u);
}

TEST(Security, AnAdminListsSessionsWithTheirTokensAndEndsOne) {
  ServerProcess server(secured_config());
  Client admin(tls_client(server, "admin", kAdminToken));
  Client controller(tls_client(server, "controller", kControllerToken));
  ObjectHandle wall = controller.add_wall({.normal = {0, 0, 1}, .impedance = {800.0, 1.0}});

  const std::vector<SessionSummary> sessions = admin.sessions();
  ASSERT_EQ(sessions.size(), 2u);
  bool found = false;
  for (const SessionSummary& session : sessions) {
    if (session.session_id != controller.session_id()) continue;
    found = true;
    EXPECT_EQ(session.client_name, "controller");
    EXPECT_EQ(session.token_name, "operator");
    EXPECT_EQ(session.role, Role::kController);
    EXPECT_EQ(session.peer, "127.0.0.1");
  }
  EXPECT_TRUE(found);

  std::mutex mutex;
  std::condition_variable told;
  std::optional<ConnectionChange> ended;
  controller.on_connection([&](const ConnectionChange& change) {
    std::lock_guard lock(mutex);
    ended = change;
    told.notify_all();
  });
  admin.kick_session(controller.session_id(), "demo over");
  const std::string kicked = refusal<PermissionDeniedError>([&] { (void)controller.step(1); });
  EXPECT_NE(kicked.find("was ended by 'root': demo over"), std::string::npos) << kicked;
  {
    // The kicked client learns it for good and does not come back with its wall.
    std::unique_lock lock(mutex);
    ASSERT_TRUE(told.wait_for(lock, std::chrono::seconds(5), [&] { return ended.has_value(); }));
    EXPECT_EQ(ended->state, ConnectionChange::State::kEnded);
    EXPECT_NE(ended->reason.find("ended by 'root': demo over"), std::string::npos) << ended->reason;
  }
  (void)admin.step(1);  // the removal ramps out over the next ticks
  EXPECT_EQ(admin.sessions().size(), 1u);
  EXPECT_EQ(admin.stats().objects, 0u);
  refusal<NotFoundError>([&] { admin.kick_session(controller.session_id()); });
  EXPECT_NO_THROW(controller.close());  // nothing left to close on the server
}

// Each TLS mismatch is refused, and the error says which setting to change (gRPC alone says
// "Connection reset by peer" or "certificate verify failed").
TEST(Security, AClientThatDoesNotTrustTheServersCaIsRefusedSayingSo) {
  ServerProcess server(secured_config());
  const std::string other_ca = refusal<ConnectionError>(
      [&] { Client client(tls_client(server, "other-ca", kAdminToken, kCerts + "/other_ca.pem")); });
  EXPECT_NE(other_ca.find("which tls.ca_file (--ca) '" + kCerts + "/other_ca.pem'"),
            std::string::npos) << other_ca;
  ClientConfig plaintext = config_for(server, "plaintext");  // no TLS at all
  plaintext.token = kAdminToken;
  const std::string no_tls = refusal<ConnectionError>([&] { Client client(plaintext); });
  EXPECT_NE(no_tls.find("the server speaks TLS: turn it on with ClientConfig::tls"), std::string::npos) << no_tls;
  ClientConfig wrong_name = tls_client(server, "wrong-name", kAdminToken);
  wrong_name.tls->server_name = "haptics.other.lab";
  const std::string name = refusal<ConnectionError>([&] { Client client(wrong_name); });
  EXPECT_NE(name.find("not 'haptics.other.lab': connect by one of them, or give one with tls.server_name"),
            std::string::npos) << name;
}

TEST(Security, ATlsClientOfAPlaintextServerIsToldTheServerDoesNotSpeakTls) {
  ServerProcess server(R"({"time_mode": "LOCKSTEP"})");
  ClientConfig config = config_for(server, "tls-to-plaintext");
  config.tls = TlsOptions{};
  config.tls->ca_file = kCerts + "/ca.pem";
  config.rpc_timeout = std::chrono::milliseconds(3000);
  const std::string message = refusal<ConnectionError>([&] { Client client(config); });
  EXPECT_NE(message.find("the server does not speak TLS"), std::string::npos) << message;
}

TEST(Security, MutualTlsRefusesAClientWithoutACertificateSayingItWantsOne) {
  ServerProcess server(secured_config(/*client_ca=*/true));
  const std::string message =
      refusal<ConnectionError>([&] { Client client(tls_client(server, "no-cert", kControllerToken)); });
  EXPECT_NE(message.find("the server asks for a client certificate (mutual TLS): give one with "
                         "tls.cert_file (--cert) and its key with tls.key_file (--key)"),
            std::string::npos) << message;
  ClientConfig with_cert = tls_client(server, "with-cert", kControllerToken);
  with_cert.tls->cert_file = kCerts + "/client.pem";
  with_cert.tls->key_file = kCerts + "/client.key";
  Client client(with_cert);
  EXPECT_EQ(client.step(1), 1u);
}

TEST(Security, ASessionEndsWhenItsTokenExpiresAndItsItemsGoWithIt) {
  // A token that expires eight seconds from now (whole seconds, as RFC 3339 writes them, so 7 to
  // 8 s are left): time enough to start the server and open the session on a loaded machine,
  // where a start alone can take a second or more.
  const std::time_t expiry = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now()) + 8;
  std::tm utc{};
  gmtime_r(&expiry, &utc);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y-%m-%dT%H:%M:%SZ", &utc);
  ServerProcess server(R"({"time_mode": "LOCKSTEP", "security": {"tokens": [
      {"name": "root", "token": ")" + std::string(kAdminToken) + R"(", "role": "ADMIN"},
      {"name": "visitor", "token": "visitor-token-0123456789", "role": "CONTROLLER",
       "expires": ")" + std::string(stamp) + R"("}]}})");
  ClientConfig admin_config = config_for(server, "admin");
  admin_config.token = kAdminToken;
  Client admin(admin_config);
  ClientConfig visitor_config = config_for(server, "visitor");
  visitor_config.token = "visitor-token-0123456789";
  ConnectionLog visitor_log;
  Client visitor(visitor_config);
  visitor_log.attach(visitor);
  ObjectHandle wall = visitor.add_wall({.normal = {0, 0, 1}, .impedance = {800.0, 1.0}});
  ASSERT_EQ(admin.stats().objects, 1u);
  ASSERT_LT(std::chrono::system_clock::now(), std::chrono::system_clock::from_time_t(expiry))
      << "starting the server and opening the session took longer than the token lives";

  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(14);
  while (admin.sessions().size() > 1 && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_EQ(admin.sessions().size(), 1u);  // the visitor's heartbeats no longer hold it
  (void)admin.step(1);                     // its wall ramps out
  EXPECT_EQ(admin.stats().objects, 0u);
  const std::string late = refusal<UnauthenticatedError>([&] { (void)visitor.step(1); });
  EXPECT_NE(late.find("token 'visitor' expired at " + std::string(stamp)), std::string::npos) << late;
  // The SDK tells its user, once, and does not try to reconnect with a token that cannot work.
  const auto ended = visitor_log.wait(1, std::chrono::seconds(10));
  ASSERT_TRUE(ended);
  EXPECT_EQ(ended->first.state, ConnectionChange::State::kEnded);
  EXPECT_NE(ended->first.reason.find("expired at " + std::string(stamp)), std::string::npos)
      << ended->first.reason;
  EXPECT_EQ(visitor.connection_state(), ConnectionChange::State::kEnded);
  EXPECT_FALSE(visitor_log.wait(2, std::chrono::milliseconds(600)));
}

TEST(Security, TokensAlsoWorkOverPlaintextOnLoopback) {
  ServerProcess server(R"({"time_mode": "LOCKSTEP", "security": {)" + tokens_json() + "}}");
  ClientConfig config = config_for(server, "plain");
  config.token = kObserverToken;
  Client observer(config);
  refusal<PermissionDeniedError>([&] { (void)observer.step(1); });
  config.token = {};
  refusal<UnauthenticatedError>([&] { Client client(config); });
}

}  // namespace
}  // namespace haptic::test
