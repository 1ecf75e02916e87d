// Who gets a control-plane connection, tried from outside on loopback (127.0.0.x are distinct
// hosts to the server), in plaintext and with TLS alike: a connection that completes no TLS
// handshake or sends no HTTP/2 preface within handshake_timeout_ms is closed; one that speaks
// something else is closed at once; at max_connections a newcomer from a host holding fewer
// displaces the oldest idle connection of the host holding most; running out of descriptors is
// survived with TLS as in plaintext. Every loop is bounded in count and time.

#include <arpa/inet.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "integration/raw_client.hpp"
#include "integration/server_process.hpp"

namespace haptic::test {
namespace {

const std::string kCerts = TEST_CERTS_DIR;

/// TLS (mutual with `mutual`) for the control plane, plus `extra` config fields.
std::string tls_config(bool mutual, const std::string& extra) {
  std::string tls = R"("security": {"tls": {"cert_file": ")" + kCerts + R"(/server.pem", "key_file": ")" +
                    kCerts + "/server.key\"";
  if (mutual) tls += R"(, "client_ca_file": ")" + kCerts + "/ca.pem\"";
  tls += "}}";
  return lockstep_config(extra.empty() ? tls : tls + ", " + extra);
}

RawTls client_tls(bool with_certificate) {
  RawTls tls;
  tls.ca_file = kCerts + "/ca.pem";
  if (with_certificate) {
    tls.cert_file = kCerts + "/client.pem";
    tls.key_file = kCerts + "/client.key";
  }
  return tls;
}

/// A TCP connection to 127.0.0.1:`port` from `source` (a loopback address), or -1.
int connect_from(const char* source, std::uint16_t port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in from{};
  from.sin_family = AF_INET;
  ::inet_pton(AF_INET, source, &from.sin_addr);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(port);
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&from), sizeof from) != 0 ||
      ::connect(fd, reinterpret_cast<sockaddr*>(&to), sizeof to) != 0) {
    ::close(fd);
    return -1;
  }
  timeval limit{0, 100'000};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &limit, sizeof limit);
  return fd;
}

/// Whether the server has closed `fd` (a read sees the end), waiting up to `within`.
bool closed_by_server(int fd, std::chrono::milliseconds within) {
  const auto give_up = std::chrono::steady_clock::now() + within;
  char byte;
  while (std::chrono::steady_clock::now() < give_up) {
    const ssize_t n = ::recv(fd, &byte, 1, 0);
    if (n == 0 || (n < 0 && errno == ECONNRESET)) return true;
  }
  return false;
}

class Gate : public ::testing::TestWithParam<bool> {  // the parameter: TLS
 protected:
  bool tls() const { return GetParam(); }
  std::string config(const std::string& extra) const {
    return tls() ? tls_config(false, extra) : lockstep_config(extra);
  }
  std::optional<RawTls> credentials() const {
    return tls() ? std::optional<RawTls>(client_tls(false)) : std::nullopt;
  }
};

TEST_P(Gate, AConnectionThatSaysNothingIsClosedAfterTheHandshakeTimeout) {
  ServerProcess server(config(R"("handshake_timeout_ms": 300)"));
  RawClient existing(server.address(), credentials());
  v1::OpenSessionResponse session;
  ASSERT_TRUE(existing.open(session, "existing").ok());
  std::vector<int> idle;
  for (int i = 0; i < 10; ++i) idle.push_back(connect_from("127.0.0.2", server.grpc_port()));
  const auto start = std::chrono::steady_clock::now();
  int closed = 0;
  for (const int fd : idle) closed += closed_by_server(fd, std::chrono::seconds(3)) ? 1 : 0;
  const double waited_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(closed, 10);
  EXPECT_GE(waited_s, 0.2) << "closed before the timeout";
  const v1::Stats stats = existing.stats(session);
  EXPECT_EQ(stats.connections_timed_out(), 10u);
  EXPECT_EQ(stats.connections_open(), 1u);  // the existing client's, served all along
  for (const int fd : idle) ::close(fd);
}

TEST_P(Gate, AClientSpeakingSomethingElseIsClosedAtOnce) {
  ServerProcess server(config(""));  // the default timeout, 5 s: the close must not wait for it
  const int fd = connect_from("127.0.0.2", server.grpc_port());
  const std::string request = "GET / HTTP/1.1\r\nHost: x\r\n\r\n";
  ASSERT_EQ(::send(fd, request.data(), request.size(), MSG_NOSIGNAL), static_cast<ssize_t>(request.size()));
  EXPECT_TRUE(closed_by_server(fd, std::chrono::seconds(2)));
  ::close(fd);
  RawClient client(server.address(), credentials());
  v1::OpenSessionResponse session;
  ASSERT_TRUE(client.open(session).ok());
  const v1::Stats stats = client.stats(session);
  EXPECT_EQ(stats.connections_timed_out(), 0u);
  EXPECT_EQ(stats.tls_handshakes_failed(), tls() ? 1u : 0u);
}

TEST_P(Gate, AtTheCapANewcomerFromAnotherHostDisplacesAnIdleConnection) {
  ServerProcess server(config(R"("max_connections": 10, "max_connections_per_peer": 20)"));
  RawClient existing(server.address(), credentials());
  v1::OpenSessionResponse session;
  ASSERT_TRUE(existing.open(session, "existing").ok());
  // One host fills the server: 9 idle connections and the existing client's make 10.
  std::vector<int> idle;
  for (int i = 0; i < 9; ++i) idle.push_back(connect_from("127.0.0.2", server.grpc_port()));
  for (int i = 0; i < 100 && existing.stats(session).connections_open() < 10; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(existing.stats(session).connections_open(), 10u);
  // One more from the same host: refused. One from a host holding none: served, in place of the
  // flooding host's oldest connection.
  const int same_host = connect_from("127.0.0.2", server.grpc_port());
  EXPECT_TRUE(closed_by_server(same_host, std::chrono::seconds(2)));
  ::close(same_host);
  RawClient newcomer(server.address(), credentials());  // from 127.0.0.1, like `existing`
  v1::OpenSessionResponse second;
  EXPECT_TRUE(newcomer.open(second, "newcomer").ok());
  EXPECT_TRUE(closed_by_server(idle.front(), std::chrono::seconds(2))) << "the oldest idle one goes";
  const v1::Stats stats = existing.stats(session);
  EXPECT_EQ(stats.connections_evicted(), 1u);
  EXPECT_EQ(stats.connections_refused(), 1u);
  EXPECT_EQ(stats.connections_open(), 10u);
  for (const int fd : idle) ::close(fd);
}

INSTANTIATE_TEST_SUITE_P(PlaintextAndTls, Gate, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& param_info) {
                           return param_info.param ? std::string("Tls") : std::string("Plaintext");
                         });

TEST(GateWithTls, TheControlPlaneAcceptsAgainAfterRunningOutOfDescriptors) {
  // 128 descriptors and caps far above that: 400 idle connections exhaust the fds themselves.
  // (gRPC's own TLS listener stopped for good at the first failed accept: deaf until a restart.)
  ServerProcess server(tls_config(true, R"("max_connections": 1000, "max_connections_per_peer": 1000)"),
                       {}, 128);
  RawClient existing(server.address(), client_tls(true));
  v1::OpenSessionResponse session;
  ASSERT_TRUE(existing.open(session, "existing").ok());
  std::vector<int> flood;
  for (int i = 0; i < 400; ++i) {
    const int fd = connect_from("127.0.0.2", server.grpc_port());
    if (fd >= 0) flood.push_back(fd);
  }
  ASSERT_EQ(flood.size(), 400u);
  v1::Stats during = existing.stats(session);
  for (int i = 0; i < 1000 && during.connections_refused() + during.connections_open() < 401; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    during = existing.stats(session);
  }
  std::printf("  TLS, flood of 400 with 128 fds: %u open, %llu refused\n", during.connections_open(),
              static_cast<unsigned long long>(during.connections_refused()));
  EXPECT_EQ(during.connections_open() + during.connections_refused(), 401u);
  EXPECT_GE(during.connections_refused(), 400u - 128u);
  for (const int fd : flood) ::close(fd);
  // A new client is served after the flood's end: what fails is a lockout (gRPC's own TLS
  // listener stopped accepting for good), not a loaded machine's slower second.
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  bool served = false;
  while (!served && std::chrono::steady_clock::now() < give_up) {
    RawClient fresh(server.address(), client_tls(true));
    v1::OpenSessionResponse again;
    served = fresh.open(again, "fresh", std::chrono::seconds(2)).ok();  // a TLS handshake under load
  }
  EXPECT_TRUE(served);
}

TEST(GateWithTls, MutualTlsCountsAClientWithoutACertificateAsAFailedHandshake) {
  ServerProcess server(tls_config(true, ""));
  RawClient without(server.address(), client_tls(false));
  v1::OpenSessionResponse refused;
  EXPECT_FALSE(without.open(refused, "no-certificate", std::chrono::milliseconds(1000)).ok());
  RawClient with(server.address(), client_tls(true));
  v1::OpenSessionResponse session;
  ASSERT_TRUE(with.open(session, "with-certificate").ok());
  EXPECT_GE(with.stats(session).tls_handshakes_failed(), 1u);
}

}  // namespace
}  // namespace haptic::test
