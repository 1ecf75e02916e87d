#include "net/metrics_endpoint.hpp"

namespace haptic::net {

void MetricsEndpoint::start(std::function<std::string()> render) {
  render_ = std::move(render);
  http_.start([this](const HttpRequest& request) { return handle(request); });
}

HttpResponse MetricsEndpoint::handle(const HttpRequest& request) {
  if (request.path == "/metrics") {
    HttpResponse response;
    response.content_type = "text/plain; version=0.0.4; charset=utf-8";
    response.body = render_();
    scrapes_.fetch_add(1, std::memory_order_relaxed);
    return response;
  }
  if (request.path == "/") {
    return HttpResponse::text(200, "hapticd: metrics in Prometheus' text format at /metrics\n");
  }
  return HttpResponse::text(404, "hapticd metrics: no " + request.path + "; see /metrics\n");
}

}  // namespace haptic::net
