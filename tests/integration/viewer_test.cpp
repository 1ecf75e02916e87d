// The web viewer's endpoint of a real hapticd (--http): the JSON resources against what a client
// registered and stepped to, the page's files, bearer tokens as the RPCs that read the same need
// them, and clear refusals of anything else, in lockstep on ephemeral loopback ports.
#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>

#include <haptic/haptic.hpp>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "haptic/v1/viewer.pb.h"
#include "integration/run_program.hpp"
#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"
#include "support/every_kind_scene.hpp"
#include "support/http_client.hpp"

namespace haptic {
namespace {

using test::http_get;
using test::HttpReply;

/// `reply`'s body parsed as `T` (the endpoint's JSON is protobuf's mapping of the viewer messages).
template <typename T>
T parse(const HttpReply& reply) {
  T message;
  const auto status = google::protobuf::util::JsonStringToMessage(reply.body, &message);
  EXPECT_TRUE(status.ok()) << status.ToString() << "\n" << reply.body.substr(0, 500);
  return message;
}

std::string object_kind(const v1::Object& object) {
  const auto* oneof = object.GetDescriptor()->FindOneofByName("shape");
  const auto* set = object.GetReflection()->GetOneofFieldDescriptor(object, oneof);
  return set == nullptr ? "" : set->name();
}

std::string field_kind(const v1::Field& field) {
  const auto* oneof = field.GetDescriptor()->FindOneofByName("kind");
  const auto* set = field.GetReflection()->GetOneofFieldDescriptor(field, oneof);
  return set == nullptr ? "" : set->name();
}

// The server's own wall (session 0) beside what the client registers.
const std::string kServerScene =
    R"("initial_scene": {"objects": [{"half_space": {"normal": {"z": 1}},
       "pose": {"position": {"z": -0.08}}, "impedance": {"stiffness": 800}}]})";

TEST(Viewer, TheSceneShowsEveryItemOfEveryKindWithItsIdAndOwner) {
  test::ServerProcess server(test::lockstep_config(kServerScene), "--http=0");
  ASSERT_NE(server.viewer_port(), 0);
  Client client(test::config_for(server, "viewer-test"));
  test::EveryKind registered = test::register_every_kind(client);

  const HttpReply reply = http_get(server.viewer_port(), "/api/scene");
  ASSERT_EQ(reply.status, 200) << reply.body;
  EXPECT_EQ(reply.header("Content-Type"), "application/json");
  EXPECT_EQ(reply.header("Cache-Control"), "no-store");
  const auto scene = parse<v1::ViewerScene>(reply);
  ASSERT_EQ(scene.devices_size(), 1);
  EXPECT_EQ(scene.devices(0).model(), "point_mass");
  EXPECT_DOUBLE_EQ(scene.devices(0).workspace_max().x(), 0.1);

  const v1::SceneContents& contents = scene.contents();
  ASSERT_EQ(contents.scene().objects_size(), static_cast<int>(registered.objects.size()) + 1);
  EXPECT_EQ(contents.object_sessions(0), 0u);  // the server's own, made first
  EXPECT_EQ(object_kind(contents.scene().objects(0)), "half_space");
  for (std::size_t i = 0; i < registered.objects.size(); ++i) {
    const int at = static_cast<int>(i) + 1;
    EXPECT_EQ(contents.object_ids(at), registered.objects[i].id());
    EXPECT_EQ(contents.object_sessions(at), client.session_id());
    EXPECT_EQ(object_kind(contents.scene().objects(at)), registered.object_kinds[i]);
  }
  ASSERT_EQ(contents.scene().fields_size(), static_cast<int>(registered.fields.size()));
  for (std::size_t i = 0; i < registered.fields.size(); ++i) {
    const int at = static_cast<int>(i);
    EXPECT_EQ(contents.field_ids(at), registered.fields[i].id());
    EXPECT_EQ(contents.field_sessions(at), client.session_id());
    EXPECT_EQ(field_kind(contents.scene().fields(at)), registered.field_kinds[i]);
  }
  // The fields as given: the box's half extents, the mesh's triangles.
  EXPECT_DOUBLE_EQ(contents.scene().objects(3).box().half_extents().x(), 0.015);
  EXPECT_EQ(contents.scene().objects(5).mesh().indices_size(), 12);

  // Removing an item moves the generation on (a page then fetches the scene again).
  const auto before = parse<v1::ViewerState>(http_get(server.viewer_port(), "/api/state"));
  EXPECT_EQ(before.scene_generation(), scene.generation());
  registered.fields.back().remove();
  const auto after = parse<v1::ViewerScene>(http_get(server.viewer_port(), "/api/scene"));
  EXPECT_GT(after.generation(), scene.generation());
  EXPECT_EQ(after.contents().scene().fields_size(), static_cast<int>(registered.fields.size()) - 1);
}

TEST(Viewer, TheStateIsTheNewestTickTheClientSteppedTo) {
  test::ServerProcess server(test::lockstep_config(), "--http=0");
  Client client(test::config_for(server, "viewer-test"));
  test::EveryKind registered = test::register_every_kind(client);
  // The hand pulls the tool into the pushable sphere (centre x = 50 mm, radius 15 mm): 100 ms
  // on, the tool is pushing it away, in contact.
  client.set_operator(OperatorInput::follow({0.05, 0.0, 0.0}, 200.0, 5.0));
  const State stepped = test::step_and_get(client, 100);

  const auto state = parse<v1::ViewerState>(http_get(server.viewer_port(), "/api/state"));
  EXPECT_EQ(state.tick(), stepped.tick);
  EXPECT_DOUBLE_EQ(state.server_time_s(), stepped.server_time);
  ASSERT_EQ(state.tools_size(), 1);
  const v1::ToolState& tool = state.tools(0);
  EXPECT_EQ(tool.tick(), stepped.tick);
  EXPECT_DOUBLE_EQ(tool.position().x(), stepped.position.x);
  EXPECT_DOUBLE_EQ(tool.position().z(), stepped.position.z);
  EXPECT_DOUBLE_EQ(tool.force().x(), stepped.force.x);
  EXPECT_DOUBLE_EQ(tool.proxy().x(), stepped.proxy.x);
  EXPECT_EQ(tool.contact_count(), stepped.contact_count);
  EXPECT_EQ(tool.contact_count(), 1u);  // on the sphere
  EXPECT_LT(tool.force().x(), 0.0);     // pushed back towards the start

  // The sphere has been pushed: where the loop moved it, as GetObjectStates says.
  const std::uint64_t sphere = registered.objects[registered.pushable_sphere].id();
  const std::vector<ObjectState> moved = client.object_states();
  ASSERT_EQ(moved.size(), 1u);
  ASSERT_EQ(state.objects_size(), 1);
  EXPECT_EQ(state.objects(0).id(), sphere);
  EXPECT_DOUBLE_EQ(state.objects(0).position().x(), moved[0].position.x);
  EXPECT_GT(state.objects(0).position().x(), 0.05);

  // The statistics: the ticks, this client among the clients, and no lateness in lockstep.
  const auto stats = parse<v1::ViewerStats>(http_get(server.viewer_port(), "/api/stats"));
  EXPECT_EQ(stats.stats().ticks(), stepped.tick);
  ASSERT_EQ(stats.stats().clients_size(), 1);
  EXPECT_EQ(stats.stats().clients(0).client_name(), "viewer-test");
  EXPECT_EQ(stats.stats().clients(0).session_id(), client.session_id());
  // A lockstep loop records no lateness: the bins' sums are the unit test's (viewer_endpoint_test).
  EXPECT_EQ(stats.lateness().samples(), 0u);
  EXPECT_EQ(stats.lateness().counts_size(), 0);
  EXPECT_DOUBLE_EQ(stats.lateness().window_s(), stats.stats().window_s());
}

TEST(Viewer, ServesThePageAndRefusesWhatItDoesNotServe) {
  test::ServerProcess server(test::lockstep_config(), "--http=0");
  const std::uint16_t port = server.viewer_port();
  const HttpReply page = http_get(port, "/");
  EXPECT_EQ(page.status, 200);
  EXPECT_EQ(page.header("Content-Type"), "text/html; charset=utf-8");
  EXPECT_NE(page.body.find("<canvas"), std::string::npos);
  EXPECT_EQ(http_get(port, "/vendor/three/three.module.js").header("Content-Type"),
            "text/javascript; charset=utf-8");

  const HttpReply post = test::http_request(port, "POST", "/api/scene");
  EXPECT_EQ(post.status, 405);
  EXPECT_EQ(post.header("Allow"), "GET, HEAD");
  EXPECT_NE(post.body.find("POST is not served here (GET, HEAD only)"), std::string::npos);
  EXPECT_EQ(test::http_request(port, "DELETE", "/api/scene").status, 405);
  const HttpReply unknown = http_get(port, "/api/objects");
  EXPECT_EQ(unknown.status, 404);
  EXPECT_NE(unknown.body.find("/api/scene, /api/state and /api/stats"), std::string::npos);
  EXPECT_EQ(http_get(port, "/../../etc/passwd").status, 404);
  EXPECT_EQ(test::http_request(port, "HEAD", "/api/state").status, 200);

  test::HttpConnection garbled(port);
  garbled.send("GET\r\n\r\n");
  const HttpReply bad = garbled.read_reply();
  EXPECT_EQ(bad.status, 400);
  EXPECT_NE(bad.body.find("the request line must be 'METHOD /path HTTP/1.x'"), std::string::npos);

  // A page from another site whose name resolves to 127.0.0.1 cannot read the API.
  const HttpReply rebound = test::http_request(port, "GET", "/api/scene", "Host: attacker.example:80\r\n");
  EXPECT_EQ(rebound.status, 403);
  EXPECT_NE(rebound.body.find("not a loopback name"), std::string::npos);
}

TEST(Viewer, AStalledConnectionHoldsNoOneElseUp) {
  test::ServerProcess server(test::lockstep_config(), "--http=0");
  test::HttpConnection stalled(server.viewer_port());
  stalled.send("GET /api/state HTTP/1.1\r\nHost: 127.0.0.1\r\n");  // and no blank line yet
  // Another browser tab meanwhile: answered, twice on one kept-alive connection.
  test::HttpConnection other(server.viewer_port());
  for (int i = 0; i < 2; ++i) {
    other.send("GET /api/state HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
    const HttpReply reply = other.read_reply();
    EXPECT_EQ(reply.status, 200);
    EXPECT_EQ(reply.header("Connection"), "keep-alive");
  }
  // The stalled one was served beside it all along: its request, finished now, is answered too.
  stalled.send("\r\n");
  EXPECT_EQ(stalled.read_reply().status, 200);
}

// One host's slowloris (64 connections each to the viewer and the metrics endpoint, trickling
// request heads, made anew as they are dropped) leaves another host's requests answered: each
// host has its share of the 32 connections (8). Bounded: 100 requests each, 30 s.
TEST(Viewer, ASlowlorisFromOneHostLeavesAnotherHostsViewerAndMetricsRequestsAnswered) {
  test::ServerProcess server(test::lockstep_config(R"("metrics_address": "127.0.0.1:0")"), "--http=0");
  std::atomic<bool> stop{false};
  std::thread slowloris([&] {
    std::vector<std::unique_ptr<test::HttpConnection>> slow;
    const std::string head = "GET /api/state HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: " + std::string(500, 'x');
    for (std::size_t sent = 0; !stop.load(); ++sent) {
      if (sent % 50 == 0) {  // every second, all of them anew (the server drops them after 2 s)
        slow.clear();
        for (int i = 0; i < 64; ++i) {
          slow.push_back(std::make_unique<test::HttpConnection>(server.viewer_port(), "127.0.0.2"));
          slow.push_back(std::make_unique<test::HttpConnection>(server.metrics_port(), "127.0.0.2"));
        }
      }
      for (auto& connection : slow) connection->send(std::string(1, head[sent % head.size()]));
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  int viewer_answered = 0, metrics_answered = 0, attempts = 0;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  for (; attempts < 100 && std::chrono::steady_clock::now() < give_up; ++attempts) {
    test::HttpConnection viewer(server.viewer_port(), "127.0.0.3");
    viewer.send("GET /api/state HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
    viewer_answered += viewer.read_reply().status == 200 ? 1 : 0;
    test::HttpConnection metrics(server.metrics_port(), "127.0.0.3");
    metrics.send("GET /metrics HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
    metrics_answered += metrics.read_reply().status == 200 ? 1 : 0;
  }
  stop.store(true);
  slowloris.join();
  std::printf("  during a slowloris of 64 + 64 connections from one host: %d of %d viewer and %d of "
              "%d metrics requests from another answered\n",
              viewer_answered, attempts, metrics_answered, attempts);
  EXPECT_EQ(attempts, 100);
  EXPECT_GE(viewer_answered, 99);
  EXPECT_GE(metrics_answered, 99);
}

TEST(Viewer, WithTokensTheDataNeedsTheRoleOfTheRpcsThatReadIt) {
  test::ServerProcess server(test::lockstep_config(R"("security": {"tokens": [
      {"name": "visitor", "token": "observer-token-0123456789", "role": "OBSERVER"},
      {"name": "lab-admin", "token": "admin-token-0123456789ab", "role": "ADMIN"}]})"),
                             "--http=0");
  const std::uint16_t port = server.viewer_port();
  const std::string observer = "Authorization: Bearer observer-token-0123456789\r\n";
  const std::string admin = "Authorization: Bearer admin-token-0123456789ab\r\n";

  const HttpReply none = http_get(port, "/api/scene");
  EXPECT_EQ(none.status, 401);
  EXPECT_EQ(none.header("WWW-Authenticate"), "Bearer realm=\"hapticd\"");
  EXPECT_NE(none.body.find("needs a bearer token"), std::string::npos) << none.body;
  const HttpReply wrong =
      http_get(port, "/api/state", "Authorization: Bearer not-a-token-of-this-server\r\n");
  EXPECT_EQ(wrong.status, 401);
  EXPECT_NE(wrong.body.find("the token is not one this server knows"), std::string::npos) << wrong.body;
  EXPECT_EQ(http_get(port, "/api/state", "Authorization: Basic dXNlcjpwYXNz\r\n").status, 401);

  EXPECT_EQ(http_get(port, "/api/scene", observer).status, 200);
  EXPECT_EQ(http_get(port, "/api/state", observer).status, 200);
  const HttpReply low = http_get(port, "/api/stats", observer);
  EXPECT_EQ(low.status, 403);
  EXPECT_NE(low.body.find("needs role ADMIN or above; token 'visitor' has role OBSERVER"), std::string::npos)
      << low.body;
  EXPECT_EQ(http_get(port, "/api/stats", admin).status, 200);
  // The page itself carries no data: it loads without a token, and asks for one.
  EXPECT_EQ(http_get(port, "/").status, 200);
  // A token never makes the endpoint writable.
  EXPECT_EQ(test::http_request(port, "PUT", "/api/scene", admin).status, 405);
}

TEST(Viewer, TheCommandLineAndTheConfigurationsRules) {
  const auto run = [](const std::vector<std::string>& args) {
    return test::run_program(HAPTICD_BINARY, args);
  };
  // A port alone is loopback's.
  const test::Outcome loopback = run({"--http", "8080", "--print-config"});
  EXPECT_EQ(loopback.exit_code, 0) << loopback.output;
  EXPECT_NE(loopback.output.find(R"("viewer_address": "127.0.0.1:8080")"), std::string::npos)
      << loopback.output;
  EXPECT_EQ(run({"--http", "localhost:x", "--print-config"}).exit_code, 2);

  // With tokens, plain HTTP off loopback would carry them in clear: refused, naming why.
  const auto dir = std::filesystem::temp_directory_path() / ("hapticd-viewer-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto config = dir / "config.json";
  std::ofstream(config) << R"({"security": {"tokens": [
      {"name": "visitor", "token": "observer-token-0123456789", "role": "OBSERVER"}]}})";
  const test::Outcome remote = run({"--config", config.string(), "--http", "0.0.0.0:0", "--print-config"});
  EXPECT_EQ(remote.exit_code, 2);
  EXPECT_NE(remote.output.find("viewer_address: '0.0.0.0:0' is not a loopback address, and the viewer "
                               "speaks plain HTTP"),
            std::string::npos)
      << remote.output;

  // A folder without the page stops the server at start, naming it: a configuration error (2).
  const test::Outcome no_page = run({"--lockstep", "--grpc-address", "127.0.0.1:0", "--udp-port", "0",
                                     "--http", "0", "--viewer-root", dir.string()});
  EXPECT_EQ(no_page.exit_code, 2);
  EXPECT_NE(no_page.output.find("viewer_root: no index.html in '" + dir.string() + "'"), std::string::npos)
      << no_page.output;
  std::filesystem::remove_all(dir);
}

TEST(Viewer, NoneWithoutAnAddress) {
  test::ServerProcess server(test::lockstep_config());
  EXPECT_EQ(server.viewer_port(), 0);
}

}  // namespace
}  // namespace haptic
