// The metrics endpoint of a real hapticd: Prometheus' text at /metrics over plain HTTP, every
// session in it, clear answers to anything else, and none without metrics_address.
#include <gtest/gtest.h>

#include <haptic/haptic.hpp>

#include <string>

#include "haptic/io/session_id.hpp"
#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"
#include "support/http_client.hpp"

namespace haptic {
namespace {

TEST(MetricsEndpoint, ServesEveryFigureAndEverySessionInPrometheusText) {
  test::ServerProcess server(test::lockstep_config(), "--metrics-address=127.0.0.1:0");
  ASSERT_NE(server.metrics_port(), 0);
  Client viewer(test::config_for(server, "viewer"));
  (void)viewer.step(25);

  const test::HttpReply reply = test::http_get(server.metrics_port(), "/metrics");
  EXPECT_EQ(reply.status, 200) << reply.head;
  EXPECT_EQ(reply.header("Content-Type"), "text/plain; version=0.0.4; charset=utf-8");
  const std::string& body = reply.body;
  EXPECT_EQ(reply.header("Content-Length"), std::to_string(body.size()));
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
  {
    test::HttpConnection connection(server.metrics_port());
    connection.send("HEAD /metrics HTTP/1.1\r\nConnection: close\r\n\r\n");
    EXPECT_EQ(connection.read_reply(true).status, 200);
    EXPECT_TRUE(connection.closed_by_server());  // no body followed
  }
  EXPECT_EQ(test::http_get(server.metrics_port(), "/").status, 200);
  const test::HttpReply missing = test::http_get(server.metrics_port(), "/metricz");
  EXPECT_EQ(missing.status, 404);
  EXPECT_NE(missing.body.find("no /metricz; see /metrics"), std::string::npos);
  EXPECT_EQ(test::http_request(server.metrics_port(), "POST", "/metrics").status, 405);
  // A request that never ends is dropped (after 2 s) and the next scrape is answered.
  {
    test::HttpConnection stalled(server.metrics_port());
    stalled.send("GET /metrics HTTP/1.1\r\n");
    EXPECT_TRUE(stalled.closed_by_server());  // a reply would leave bytes; 5 s would be a timeout
  }
  EXPECT_EQ(test::http_get(server.metrics_port(), "/metrics").status, 200);
}

TEST(MetricsEndpoint, NoneWithoutAMetricsAddress) {
  test::ServerProcess server(test::lockstep_config());
  EXPECT_EQ(server.metrics_port(), 0);
}

}  // namespace
}  // namespace haptic
