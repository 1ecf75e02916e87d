#pragma once
// GetStats in Prometheus' text exposition format (version 0.0.4), for the metrics endpoint.
// Names follow Prometheus' conventions: the `hapticd_` prefix, base units in the name (seconds,
// hertz), `_total` on counters; per-client series carry `session` (16 hex digits, as the log writes
// it) and `client` labels. Percentiles over the sliding window are gauges with a `quantile` label.
// A server in a federation adds the `hapticd_federation_` families: its counters, and per coupling
// across the network its layer's books, labelled `kind` (tool or mass), `port` (a tool's), `remote`
// and `mass` (a mass's; keys as 16 hex digits); a server without one writes none of them.

#include <string>

#include "haptic/v1/service.pb.h"

namespace haptic::net {

/// The exposition of `stats`: HELP and TYPE once per metric, then its samples.
std::string prometheus_text(const v1::Stats& stats);

/// A label value escaped as the format asks: backslash, double quote and newline.
std::string escape_label_value(const std::string& value);

}  // namespace haptic::net
