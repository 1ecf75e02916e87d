// The viewer's endpoint without sockets: the page's files, the JSON resources built from a scene
// store, a sample ring and a lateness histogram, and each request's refusals (tokens, Host).
#include <gtest/gtest.h>

#include <google/protobuf/util/json_util.h>

#include <filesystem>
#include <fstream>

#include "net/viewer_endpoint.hpp"
#include "runtime/realtime.hpp"

namespace haptic::net {
namespace {

class ViewerEndpointTest : public ::testing::Test {
 protected:
  static constexpr std::int64_t kNow = 5'000'000'000;  // the statistics' clock, ns

  void SetUp() override {
    root_ = std::filesystem::temp_directory_path() / ("viewer-endpoint-test-" + std::to_string(::getpid()));
    std::filesystem::create_directories(root_ / "vendor");
    std::ofstream(root_ / "index.html") << "<!doctype html><canvas></canvas>";
    std::ofstream(root_ / "vendor" / "lib.js") << "export {};";
  }
  void TearDown() override { std::filesystem::remove_all(root_); }

  /// The sources over this fixture's store, ring and histogram, with `credentials`.
  ViewerSources sources(std::vector<Credential> credentials = {}) {
    ViewerSources out;
    out.scene = &store_;
    out.samples = {&ring_};
    out.devices.emplace_back().set_model("point_mass");
    // As Server::stats: the lateness figures and bins from one reading of the histogram.
    out.stats = [this](runtime::LatenessHistogram::Counts& lateness_bins) {
      const runtime::LatenessSummary lateness = lateness_.summarize(kNow, lateness_bins);
      v1::Stats stats;
      stats.set_ticks(42);
      stats.set_window_s(lateness.window_s);
      stats.set_lateness_samples(lateness.samples);
      return stats;
    };
    out.access = AccessControl(std::move(credentials));
    return out;
  }

  static HttpRequest get(const std::string& path, const std::string& authorization = {},
                         const std::string& host = "127.0.0.1:8080") {
    HttpRequest request;
    request.method = "GET";
    request.path = path;
    request.headers["host"] = host;
    if (!authorization.empty()) request.headers["authorization"] = authorization;
    return request;
  }

  std::filesystem::path root_;
  runtime::SceneExchange exchange_{std::make_unique<const engine::CompiledScene>()};
  SceneStore store_{exchange_, [] { return std::int64_t{1}; }, 50, 8};
  runtime::SampleRing ring_;
  runtime::LatenessHistogram lateness_;
};

TEST_F(ViewerEndpointTest, ServesThePagesFilesByPathAndNothingElse) {
  ViewerEndpoint endpoint(sources());
  endpoint.load_page(root_);
  const HttpResponse page = endpoint.handle(get("/"));
  EXPECT_EQ(page.status, 200);
  EXPECT_EQ(page.content_type, "text/html; charset=utf-8");
  EXPECT_EQ(page.body, "<!doctype html><canvas></canvas>");
  EXPECT_EQ(endpoint.handle(get("/vendor/lib.js")).content_type, "text/javascript; charset=utf-8");
  EXPECT_EQ(endpoint.handle(get("/vendor/../index.html")).status, 404);  // only the files' own paths
  EXPECT_EQ(endpoint.handle(get("/missing.js")).body, "hapticd viewer: no /missing.js; the page is at /\n");

  std::filesystem::remove(root_ / "index.html");
  try {
    endpoint.load_page(root_);
    FAIL() << "a folder without index.html was taken";
  } catch (const std::runtime_error& error) {
    EXPECT_EQ(std::string(error.what()).rfind("viewer_root: no index.html in '" + root_.string() + "'", 0),
              0u)
        << error.what();
  }
}

TEST_F(ViewerEndpointTest, TheStateIsEachPortsNewestSample) {
  const ViewerSources from = sources();
  v1::ViewerState state = viewer_state(from);
  EXPECT_EQ(state.tick(), 0u);  // nothing published yet: the port is there, empty
  ASSERT_EQ(state.tools_size(), 1);
  EXPECT_EQ(state.tools(0).tick(), 0u);

  for (std::uint64_t tick = 1; tick <= 3; ++tick) {
    runtime::TickSample sample;
    sample.tick = tick;
    sample.time_ns = static_cast<std::int64_t>(tick - 1) * 1'000'000;
    sample.p_WT = {0.01 * static_cast<double>(tick), 0.0, 0.02};
    sample.F_T_W = {0.0, 0.0, 1.5};
    sample.contact_count = 1;
    ring_.publish(sample);
  }
  state = viewer_state(from);
  EXPECT_EQ(state.tick(), 3u);
  EXPECT_DOUBLE_EQ(state.server_time_s(), 0.002);
  EXPECT_DOUBLE_EQ(state.tools(0).position().x(), 0.03);
  EXPECT_DOUBLE_EQ(state.tools(0).force().z(), 1.5);
  EXPECT_EQ(state.tools(0).contact_count(), 1u);
  EXPECT_EQ(state.scene_generation(), store_.generation());
}

TEST_F(ViewerEndpointTest, TheHistogramHoldsTheWindowsNonEmptyBinsInOrder) {
  for (int i = 0; i < 980; ++i) lateness_.record(10'000, kNow);    // 10 µs: a fine bin
  for (int i = 0; i < 20; ++i) lateness_.record(2'550'000, kNow);  // 2.55 ms: the coarse bin at 2.5 ms
  const double before_s = static_cast<double>(runtime::monotonic_now_ns()) * 1e-9;
  const v1::ViewerStats stats = viewer_stats(sources());
  const double after_s = static_cast<double>(runtime::monotonic_now_ns()) * 1e-9;
  EXPECT_EQ(stats.stats().ticks(), 42u);
  // When they were read, on the server's clock: the page's rate now is timed by it.
  EXPECT_GE(stats.read_at_s(), before_s);
  EXPECT_LE(stats.read_at_s(), after_s);
  const v1::LatenessHistogram& histogram = stats.lateness();
  EXPECT_EQ(histogram.samples(), 1000u);
  EXPECT_EQ(stats.stats().lateness_samples(), 1000u);  // the figures and the bins: one reading
  EXPECT_DOUBLE_EQ(histogram.window_s(), 10.0);
  ASSERT_EQ(histogram.counts_size(), 2);
  EXPECT_DOUBLE_EQ(histogram.bin_lower_us(0), 10.0);
  EXPECT_DOUBLE_EQ(histogram.bin_width_us(0), 1.0);
  EXPECT_EQ(histogram.counts(0), 980u);
  EXPECT_DOUBLE_EQ(histogram.bin_lower_us(1), 2500.0);
  EXPECT_DOUBLE_EQ(histogram.bin_width_us(1), 100.0);
  EXPECT_EQ(histogram.counts(1), 20u);
}

TEST_F(ViewerEndpointTest, EachResourceNeedsTheRoleOfTheRpcThatReadsTheSame) {
  ViewerEndpoint endpoint(sources({{"visitor", "observer-secret-0001", v1::OBSERVER, std::nullopt},
                                   {"root", "admin-secret-0000001", v1::ADMIN, std::nullopt}}));
  const HttpResponse none = endpoint.handle(get("/api/state"));
  EXPECT_EQ(none.status, 401);
  EXPECT_EQ(
      none.body.rfind("hapticd viewer: GET /api/state: authorization: this server needs a bearer token", 0),
      0u)
      << none.body;
  EXPECT_EQ(endpoint.handle(get("/api/state", "Bearer observer-secret-0001")).status, 200);
  EXPECT_EQ(endpoint.handle(get("/api/scene", "Bearer observer-secret-0001")).status, 200);
  const HttpResponse stats = endpoint.handle(get("/api/stats", "Bearer observer-secret-0001"));
  EXPECT_EQ(stats.status, 403);
  EXPECT_EQ(stats.body,
            "hapticd viewer: GET /api/stats: needs role ADMIN or above; token 'visitor' has role OBSERVER\n");
  const HttpResponse admin = endpoint.handle(get("/api/stats", "Bearer admin-secret-0000001"));
  ASSERT_EQ(admin.status, 200);
  EXPECT_EQ(admin.content_type, "application/json");
  v1::ViewerStats parsed;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(admin.body, &parsed).ok()) << admin.body;
  EXPECT_EQ(parsed.stats().ticks(), 42u);
  // Zero figures are written out, not left for the reader to guess.
  EXPECT_NE(admin.body.find("\"overruns\":\"0\""), std::string::npos) << admin.body;
}

TEST_F(ViewerEndpointTest, ALoopbackViewerAnswersOnlyToLoopbackNames) {
  ViewerEndpoint endpoint(sources());
  for (const char* host : {"127.0.0.1:8080", "localhost:8080", "[::1]:8080", "127.0.0.2", "localhost"}) {
    EXPECT_EQ(endpoint.handle(get("/api/state", {}, host)).status, 200) << host;
  }
  for (const char* host :
       {"attacker.example", "attacker.example:8080", "127.0.0.1.attacker.example", "10.0.0.2:8080"}) {
    EXPECT_EQ(endpoint.handle(get("/api/state", {}, host)).status, 403) << host;
  }
  // Bound elsewhere: an address, or the name it was configured with; no other name.
  ViewerSources remote = sources();
  remote.loopback_only = false;
  remote.host_name = "viewer.lab";
  const ViewerEndpoint remote_endpoint(std::move(remote));
  for (const char* host : {"viewer.lab:8080", "192.168.10.20:8080", "[fe80::1]:8080", "localhost:8080"}) {
    EXPECT_EQ(remote_endpoint.handle(get("/api/state", {}, host)).status, 200) << host;
  }
  for (const char* host : {"attacker.example:8080", "dead.beef:8080", "cafe"}) {
    const HttpResponse rebound = remote_endpoint.handle(get("/api/state", {}, host));
    EXPECT_EQ(rebound.status, 403) << host;
    EXPECT_NE(rebound.body.find("neither an address nor 'viewer.lab'"), std::string::npos) << rebound.body;
  }
}

TEST_F(ViewerEndpointTest, AnHttp11RequestWithoutAHostIsRefused) {
  ViewerEndpoint endpoint(sources());
  HttpRequest request = get("/api/state");
  request.headers.erase("host");
  request.version = "HTTP/1.1";
  const HttpResponse refused = endpoint.handle(request);
  EXPECT_EQ(refused.status, 400);
  EXPECT_NE(refused.body.find("must name its Host"), std::string::npos) << refused.body;
  request.version = "HTTP/1.0";  // which has no Host to send
  EXPECT_EQ(endpoint.handle(request).status, 200);
}

}  // namespace
}  // namespace haptic::net
