// The metrics endpoint of a real hapticd: Prometheus' text at /metrics over plain HTTP, every
// session in it, clear answers to anything else, and none without metrics_address.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <haptic/haptic.hpp>

#include <string>

#include "haptic/io/session_id.hpp"
#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"

namespace haptic {
namespace {

/// Sends `request` to 127.0.0.1:`port` and returns all the server answers before it closes.
std::string http(std::uint16_t port, const std::string& request) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(port);
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  timeval timeout{5, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  std::string reply;
  if (::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0) {
    (void)::send(fd, request.data(), request.size(), MSG_NOSIGNAL);
    char buffer[4096];
    for (ssize_t got; (got = ::recv(fd, buffer, sizeof buffer, 0)) > 0;) {
      reply.append(buffer, static_cast<std::size_t>(got));
    }
  }
  ::close(fd);
  return reply;
}

std::string get(std::uint16_t port, const std::string& path) {
  return http(port, "GET " + path + " HTTP/1.1\r\nHost: localhost\r\n\r\n");
}

TEST(MetricsEndpoint, ServesEveryFigureAndEverySessionInPrometheusText) {
  test::ServerProcess server(test::lockstep_config(), "--metrics-address=127.0.0.1:0");
  ASSERT_NE(server.metrics_port(), 0);
  Client viewer(test::config_for(server, "viewer"));
  (void)viewer.step(25);

  const std::string reply = get(server.metrics_port(), "/metrics");
  EXPECT_EQ(reply.rfind("HTTP/1.1 200 OK\r\n", 0), 0u) << reply.substr(0, 200);
  EXPECT_NE(reply.find("Content-Type: text/plain; version=0.0.4; charset=utf-8\r\n"), std::string::npos);
  const std::string body = reply.substr(reply.find("\r\n\r\n") + 4);
  EXPECT_NE(reply.find("Content-Length: " + std::to_string(body.size()) + "\r\n"), std::string::npos);
  EXPECT_NE(body.find("# TYPE hapticd_loop_ticks_total counter\nhapticd_loop_ticks_total 25\n"),
            std::string::npos)
      << body;
  EXPECT_NE(body.find("hapticd_sessions 1\n"), std::string::npos);
  // The session under the id the log writes.
  EXPECT_NE(body.find("hapticd_client_heartbeats_total{session=\"" +
                      io::format_session_id(viewer.session_id()) + "\",client=\"viewer\"}"),
            std::string::npos)
      << body;

  // HEAD: the head alone. Anything else: a status that says what is wrong.
  const std::string head = http(server.metrics_port(), "HEAD /metrics HTTP/1.1\r\n\r\n");
  EXPECT_EQ(head.rfind("HTTP/1.1 200 OK\r\n", 0), 0u);
  EXPECT_EQ(head.substr(head.find("\r\n\r\n") + 4), "");
  EXPECT_EQ(get(server.metrics_port(), "/").rfind("HTTP/1.1 200 OK\r\n", 0), 0u);
  const std::string missing = get(server.metrics_port(), "/metricz");
  EXPECT_EQ(missing.rfind("HTTP/1.1 404 Not Found\r\n", 0), 0u);
  EXPECT_NE(missing.find("no /metricz; see /metrics"), std::string::npos);
  EXPECT_EQ(http(server.metrics_port(), "POST /metrics HTTP/1.1\r\n\r\n").rfind("HTTP/1.1 405", 0), 0u);
  // A request that never ends is dropped (after 2 s) and the next scrape is answered.
  EXPECT_EQ(http(server.metrics_port(), "GET /metrics HTTP/1.1\r\n"), "");
  EXPECT_EQ(get(server.metrics_port(), "/metrics").rfind("HTTP/1.1 200 OK\r\n", 0), 0u);
}

TEST(MetricsEndpoint, NoneWithoutAMetricsAddress) {
  test::ServerProcess server(test::lockstep_config());
  EXPECT_EQ(server.metrics_port(), 0);
}

}  // namespace
}  // namespace haptic
