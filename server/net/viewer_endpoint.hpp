#pragma once
// The web viewer's endpoint (hapticd --http; docs/viewer.md): the page's files and three
// read-only JSON resources over net::HttpServer, on its own thread. It reads what the control
// plane reads (the scene store, the sample rings' published ticks, the statistics), never the loop,
// and changes nothing: GET and HEAD only.
//
//   /api/scene  ViewerScene: every item, its id and owner, each device port's device
//   /api/state  ViewerState: each port's newest tool sample, the virtual masses, the scene's generation
//   /api/stats  ViewerStats: GetStats' figures and the loop's lateness histogram
//
// With tokens, /api/scene and /api/state need a bearer token of role OBSERVER or above (as
// GetScene and GetObjectStates do) and /api/stats one of role ADMIN (as GetStats does): 401
// without a token the server knows, 403 with a role too low, each naming why. The page's own files
// carry no data and need none.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "haptic/v1/viewer.pb.h"
#include "net/access_control.hpp"
#include "net/http_server.hpp"
#include "net/scene_store.hpp"
#include "net/static_files.hpp"
#include "runtime/loop_stats.hpp"
#include "runtime/sample_ring.hpp"

namespace haptic::net {

/// What the viewer reads, all owned by the server and outliving the endpoint.
struct ViewerSources {
  const SceneStore* scene = nullptr;
  std::vector<const runtime::SampleRing*> samples;  // per device port, port 0 first; not empty
  std::vector<v1::DeviceInfo> devices;              // per device port, as GetDeviceInfo tells them
  /// GetStats' figures, and the loop's lateness histogram bin by bin from the same reading
  /// (the window its lateness percentiles summarize).
  std::function<v1::Stats(runtime::LatenessHistogram::Counts& lateness_bins)> stats;
  AccessControl access;  // no tokens: every request may read
  /// Against DNS rebinding (a page from another site whose name was made to resolve to this
  /// host): a request must name in its Host header a loopback name, or, when the viewer is bound
  /// to another address, an IP address or this name (the host of viewer_address). An HTTP/1.1
  /// request without Host is refused too.
  bool loopback_only = true;
  std::string host_name;  ///< the host of viewer_address, as configured
};

/// The bodies of the JSON resources, built off the loop from `sources` (for the endpoint and tests).
v1::ViewerScene viewer_scene(const ViewerSources& sources);
v1::ViewerState viewer_state(const ViewerSources& sources);
v1::ViewerStats viewer_stats(const ViewerSources& sources);

class ViewerEndpoint {
 public:
  explicit ViewerEndpoint(ViewerSources sources) : sources_(std::move(sources)) {}

  /// Listens on "host:port" (port 0 picks one). Throws std::runtime_error naming what failed.
  void bind(const std::string& address) { http_.bind(address, "viewer_address"); }
  std::uint16_t port() const { return http_.port(); }
  /// Reads the page from `root` (the built web/ folder). Throws naming viewer_root when it is not
  /// there.
  void load_page(const std::filesystem::path& root) { page_.load(root, "viewer_root"); }

  void start();
  void stop() { http_.stop(); }

  /// One request's reply (on the endpoint's thread).
  HttpResponse handle(const HttpRequest& request) const;

 private:
  ViewerSources sources_;
  StaticFiles page_;
  HttpServer http_{"viewer"};
};

}  // namespace haptic::net
