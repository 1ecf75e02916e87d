#include "net/viewer_endpoint.hpp"

#include <stdexcept>

#include "net/proto_json.hpp"
#include "net/read_back.hpp"
#include "runtime/realtime.hpp"

namespace haptic::net {
namespace {

/// The host a Host header names, without its port or an IPv6 address's brackets.
std::string host_of_header(const std::string& host_header) {
  if (!host_header.empty() && host_header.front() == '[') {
    const auto close = host_header.find(']');
    return host_header.substr(1, close == std::string::npos ? std::string::npos : close - 1);
  }
  return host_header.substr(0, host_header.rfind(':'));
}

bool loopback_name(const std::string& host) {
  if (host == "localhost" || host == "::1") return true;
  return host.rfind("127.", 0) == 0 && host.find_first_not_of("0123456789.") == std::string::npos;
}

/// An IPv4 or IPv6 address written out, which no DNS answer stands behind.
bool address_literal(const std::string& host) {
  // A name has no colon, and "dead.beef" is a name: only digits and dots, or a colon among hex.
  return !host.empty() && (host.find_first_not_of("0123456789.") == std::string::npos ||
                           (host.find(':') != std::string::npos &&
                            host.find_first_not_of("0123456789abcdefABCDEF:.") == std::string::npos));
}

/// Empty when the request may be answered; else why not (see ViewerSources::loopback_only).
std::string host_refusal(const HttpRequest& request, const ViewerSources& sources, std::uint16_t port) {
  const std::string* header = request.header("host");
  if (header == nullptr) {
    return request.version == "HTTP/1.0" ? std::string() : "an HTTP/1.1 request must name its Host";
  }
  const std::string host = host_of_header(*header);
  if (loopback_name(host)) return {};
  if (sources.loopback_only) {
    return "Host '" + *header + "' is not a loopback name, and this viewer serves loopback only: open it as "
           "http://127.0.0.1:" + std::to_string(port) + "/";
  }
  if (address_literal(host) || host == sources.host_name) return {};
  return "Host '" + *header + "' is neither an address nor '" + sources.host_name +
         "' (viewer_address's host): open the viewer by one of those";
}

HttpResponse json_response(const google::protobuf::Message& message) {
  HttpResponse response;
  response.content_type = "application/json";
  response.body = to_json(message);
  response.headers.emplace_back("Cache-Control", "no-store");
  return response;
}

}  // namespace

v1::ViewerScene viewer_scene(const ViewerSources& sources) {
  v1::ViewerScene scene;
  // The generation first: a change after it shows as a newer one in the next /api/state.
  scene.set_generation(sources.scene->generation());
  for (const v1::DeviceInfo& device : sources.devices) *scene.add_devices() = device;
  *scene.mutable_contents() = to_scene_contents(sources.scene->read(0, true));
  return scene;
}

v1::ViewerState viewer_state(const ViewerSources& sources) {
  v1::ViewerState state;
  state.set_scene_generation(sources.scene->generation());
  for (std::size_t port = 0; port < sources.samples.size(); ++port) {
    v1::ToolState& tool = *state.add_tools();
    // The newest slot can be overwritten between newest() and read() when this thread is held off
    // for a whole ring's length: then the newer newest is read, a few times at most.
    runtime::TickSample sample;
    bool read = false;
    for (int attempt = 0; attempt < 4 && !read; ++attempt) {
      const std::uint64_t newest = sources.samples[port]->newest();
      if (newest == 0) break;
      read = sources.samples[port]->read(newest, sample);
    }
    if (!read) continue;  // no sample yet: an empty ToolState holds the port's place
    tool = to_tool_state(sample);
    if (port == 0) {
      state.set_tick(sample.tick);
      state.set_server_time_s(tool.server_time_s());
    }
  }
  *state.mutable_objects() = to_object_states(sources.scene->motions()).objects();
  return state;
}

v1::ViewerStats viewer_stats(const ViewerSources& sources) {
  v1::ViewerStats out;
  runtime::LatenessHistogram::Counts counts;
  *out.mutable_stats() = sources.stats(counts);
  out.set_read_at_s(static_cast<double>(runtime::monotonic_now_ns()) * 1e-9);
  v1::LatenessHistogram& histogram = *out.mutable_lateness();
  histogram.set_window_s(out.stats().window_s());
  histogram.set_samples(out.stats().lateness_samples());
  for (std::size_t bin = 0; bin < counts.size(); ++bin) {
    if (counts[bin] == 0) continue;
    histogram.add_bin_lower_us(runtime::LatenessHistogram::bin_lower_edge_us(bin));
    histogram.add_bin_width_us(runtime::LatenessHistogram::bin_width_us(bin));
    histogram.add_counts(counts[bin]);
  }
  return out;
}

void ViewerEndpoint::start() {
  http_.start([this](const HttpRequest& request) { return handle(request); });
}

HttpResponse ViewerEndpoint::handle(const HttpRequest& request) const {
  if (const std::string refusal = host_refusal(request, sources_, port()); !refusal.empty()) {
    return HttpResponse::text(request.header("host") == nullptr ? 400 : 403,
                              "hapticd viewer: " + refusal + "\n");
  }
  if (request.path.rfind("/api/", 0) != 0) {
    if (const HttpResponse* file = page_.find(request.path)) return *file;
    return HttpResponse::text(404, "hapticd viewer: no " + request.path + "; the page is at /\n");
  }
  const bool scene = request.path == "/api/scene";
  const bool state = request.path == "/api/state";
  const bool stats = request.path == "/api/stats";
  if (!scene && !state && !stats) {
    return HttpResponse::text(404, "hapticd viewer: no " + request.path +
                                       "; the resources are /api/scene, /api/state and /api/stats\n");
  }
  // The permission of the RPC that reads the same: GetScene/GetObjectStates, GetStats.
  const std::string call = "GET " + request.path;
  const grpc::Status allowed = sources_.access.authorize_header(
      request.header("authorization"), stats ? Permission::kAdmin : Permission::kObserve, call.c_str(),
      nullptr, std::chrono::system_clock::now(), request.peer);
  if (!allowed.ok()) {
    const bool unauthenticated = allowed.error_code() == grpc::StatusCode::UNAUTHENTICATED;
    HttpResponse refusal = HttpResponse::text(
        unauthenticated ? 401 : 403, "hapticd viewer: " + call + ": " + allowed.error_message() + "\n");
    if (unauthenticated) refusal.headers.emplace_back("WWW-Authenticate", "Bearer realm=\"hapticd\"");
    return refusal;
  }
  if (scene) return json_response(viewer_scene(sources_));
  if (state) return json_response(viewer_state(sources_));
  return json_response(viewer_stats(sources_));
}

}  // namespace haptic::net
