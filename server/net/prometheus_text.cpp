#include "net/prometheus_text.hpp"

#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "haptic/io/session_id.hpp"

namespace haptic::net {
namespace {

/// Writes one metric family: its HELP and TYPE lines, then each sample.
class Exposition {
 public:
  void family(const char* name, const char* type, const char* help) {
    text_ += "# HELP ";
    text_ += name;
    text_ += ' ';
    text_ += help;
    text_ += "\n# TYPE ";
    text_ += name;
    text_ += ' ';
    text_ += type;
    text_ += '\n';
  }
  void sample(const char* name, double value, const std::string& labels = {}) {
    text_ += name;
    if (!labels.empty()) {
      text_ += '{';
      text_ += labels;
      text_ += '}';
    }
    char number[32];
    std::snprintf(number, sizeof number, " %.17g\n", value);
    text_ += number;
  }
  /// A family with one unlabelled sample.
  void single(const char* name, const char* type, const char* help, double value) {
    family(name, type, help);
    sample(name, value);
  }
  /// p50, p99 and p99.9 of a sliding-window distribution given in µs, written in seconds: a
  /// summary's quantiles (its family typed "summary"). No _sum or _count: over a sliding window
  /// neither would be the monotonic counter Prometheus takes them for.
  void quantiles_us(const char* name, double p50_us, double p99_us, double p999_us,
                    const std::string& labels = {}) {
    const std::string prefix = labels.empty() ? std::string() : labels + ",";
    sample(name, p50_us * 1e-6, prefix + "quantile=\"0.5\"");
    sample(name, p99_us * 1e-6, prefix + "quantile=\"0.99\"");
    sample(name, p999_us * 1e-6, prefix + "quantile=\"0.999\"");
  }
  std::string take() { return std::move(text_); }

 private:
  std::string text_;
};

std::string client_labels(const v1::ClientStats& client) {
  return "session=\"" + io::format_session_id(client.session_id()) + "\",client=\"" +
         escape_label_value(client.client_name()) + "\"";
}

/// A coupling's labels: its kind, and for a tool this site's port and the remote tool's key, for a
/// shared mass the other site's key and the mass's key (keys as 16 hex digits, as session ids).
std::string coupling_labels(const v1::CouplingStats& coupling) {
  const std::string remote = "remote=\"" + io::format_session_id(coupling.remote()) + "\"";
  if (coupling.kind() == v1::CouplingStats::MASS) {
    return "kind=\"mass\"," + remote + ",mass=\"" + io::format_session_id(coupling.mass()) + "\"";
  }
  return "kind=\"tool\",port=\"" + std::to_string(coupling.port()) + "\"," + remote;
}

/// The federation's counters and every coupling's books; written only by a server in one.
void federation_metrics(Exposition& e, const v1::FederationStats& f) {
  e.single("hapticd_federation_samples_published_total", "counter",
           "Tool and mass-copy samples this site published.",
           static_cast<double>(f.samples_published()));
  e.single("hapticd_federation_samples_failed_total", "counter",
           "Tool and mass-copy publications DDS refused.", static_cast<double>(f.samples_failed()));
  e.single("hapticd_federation_items_published_total", "counter",
           "Versions of this site's across_sites items sent.",
           static_cast<double>(f.items_published()));
  e.single("hapticd_federation_items_applied_total", "counter",
           "Other sites' item versions applied to this site's scene.",
           static_cast<double>(f.items_applied()));
  e.single("hapticd_federation_items_refused_total", "counter",
           "Other sites' item versions this site's checks refused.",
           static_cast<double>(f.items_refused()));
  e.single("hapticd_federation_wrenches_accepted_total", "counter",
           "ROS 2 wrenches taken into the ports' mailboxes.",
           static_cast<double>(f.wrenches_accepted()));
  e.single("hapticd_federation_wrenches_refused_total", "counter",
           "ROS 2 wrenches refused (frame, not finite).", static_cast<double>(f.wrenches_refused()));
  e.single("hapticd_federation_samples_refused_total", "counter",
           "Other sites' tool and mass samples refused (another site's name, not finite, cut off).",
           static_cast<double>(f.samples_refused()));
  e.single("hapticd_federation_energy_refused_joules_total", "counter",
           "Energy other sites claimed to have sent and were not credited (over the cap).", f.energy_refused_j());
  e.single("hapticd_federation_sites_cut_off_total", "counter",
           "Sites cut off because their energy books did not add up.", static_cast<double>(f.sites_cut_off()));
  // The four books only grow while a coupling lasts (a new coupling starts them at 0); what its
  // layer holds goes up and down.
  e.family("hapticd_federation_coupling_energy_joules_total", "counter",
           "A coupling's books at this site: put in by this site's user (book=injected), given to "
           "it (given), sent to the other site (sent), received from it (received).");
  for (const v1::CouplingStats& coupling : f.couplings()) {
    const std::string labels = coupling_labels(coupling) + ",book=";
    e.sample("hapticd_federation_coupling_energy_joules_total", coupling.injected_j(),
             labels + "\"injected\"");
    e.sample("hapticd_federation_coupling_energy_joules_total", coupling.given_j(),
             labels + "\"given\"");
    e.sample("hapticd_federation_coupling_energy_joules_total", coupling.sent_j(),
             labels + "\"sent\"");
    e.sample("hapticd_federation_coupling_energy_joules_total", coupling.received_j(),
             labels + "\"received\"");
  }
  e.family("hapticd_federation_coupling_reservoir_joules", "gauge",
           "What a coupling's passivity layer holds at this site now: injected - given + received "
           "- sent.");
  for (const v1::CouplingStats& coupling : f.couplings()) {
    e.sample("hapticd_federation_coupling_reservoir_joules", coupling.reservoir_j(),
             coupling_labels(coupling));
  }
}

}  // namespace

std::string escape_label_value(const std::string& value) {
  std::string out;
  out.reserve(value.size());
  for (const char c : value) {
    if (c == '\\') {
      out += "\\\\";
    } else if (c == '"') {
      out += "\\\"";
    } else if (c == '\n') {
      out += "\\n";
    } else {
      out += c;
    }
  }
  return out;
}

std::string prometheus_text(const v1::Stats& s) {
  Exposition e;
  e.single("hapticd_loop_ticks_total", "counter", "Loop ticks run (from 1 again after a lockstep reset).",
           static_cast<double>(s.ticks()));
  e.single("hapticd_loop_rate_hertz", "gauge", "Ticks per second achieved since the loop started.",
           s.achieved_rate_hz());
  e.single("hapticd_loop_overruns_total", "counter", "Loop periods missed because a tick ran late.",
           static_cast<double>(s.overruns()));
  e.family("hapticd_loop_lateness_seconds", "summary",
           "How late the loop woke for its ticks, over the sliding window (quantiles).");
  e.quantiles_us("hapticd_loop_lateness_seconds", s.lateness_p50_us(), s.lateness_p99_us(),
                 s.lateness_p999_us());
  e.single("hapticd_loop_lateness_max_seconds", "gauge",
           "The latest wake-up in the sliding window.", s.lateness_max_us() * 1e-6);
  e.single("hapticd_stats_window_seconds", "gauge",
           "The sliding window of the lateness and send-delay quantiles (whole seconds before this one).",
           s.window_s());
  e.family("hapticd_send_delay_seconds", "summary",
           "From a tick's time stamp to its first state datagram leaving, over the sliding window.");
  e.quantiles_us("hapticd_send_delay_seconds", s.send_delay_p50_us(), s.send_delay_p99_us(),
                 s.send_delay_p999_us());
  e.single("hapticd_sessions", "gauge", "Sessions open.", s.sessions());
  e.single("hapticd_scene_objects", "gauge", "Objects in the scene, every session's.", s.objects());
  e.single("hapticd_scene_fields", "gauge", "Fields in the scene, every session's.", s.fields());
  e.single("hapticd_udp_datagrams_sent_total", "counter", "State datagrams sent.",
           static_cast<double>(s.datagrams_sent()));
  e.single("hapticd_udp_datagrams_received_total", "counter",
           "Heartbeats and path responses accepted.", static_cast<double>(s.datagrams_received()));
  e.single("hapticd_udp_datagrams_dropped_total", "counter",
           "Datagrams refused: malformed, unauthenticated, stale, over budget or foreign.",
           static_cast<double>(s.datagrams_dropped()));
  e.single("hapticd_udp_heartbeats_rate_limited_total", "counter",
           "Heartbeats over their session's budget (of the dropped).",
           static_cast<double>(s.heartbeats_rate_limited()));
  e.single("hapticd_udp_datagrams_foreign_source_total", "counter",
           "Datagrams from another host than their session's (of the dropped).",
           static_cast<double>(s.datagrams_foreign_source()));
  e.single("hapticd_udp_path_challenges_sent_total", "counter",
           "Challenges sent to UDP addresses not yet proven to receive.",
           static_cast<double>(s.path_challenges_sent()));
  e.single("hapticd_udp_samples_skipped_total", "counter",
           "State samples not sent because a newer one was ready for the same client.",
           static_cast<double>(s.samples_skipped()));
  e.single("hapticd_udp_samples_missed_total", "counter",
           "State samples due to a client that the loop's ring overwrote before the sender read them.",
           static_cast<double>(s.samples_missed()));
  e.single("hapticd_udp_ack_stalls_total", "counter",
           "Lockstep flow-controlled streams sent on without waiting after 1 s with no acknowledgement.",
           static_cast<double>(s.ack_stalls()));
  e.single("hapticd_grpc_connections_open", "gauge", "Control-plane connections open.",
           s.connections_open());
  e.single("hapticd_grpc_connections_refused_total", "counter",
           "Control-plane connections refused (over a cap, or no descriptor left).",
           static_cast<double>(s.connections_refused()));
  e.single("hapticd_grpc_connections_timed_out_total", "counter",
           "Control-plane connections closed for no TLS handshake or HTTP/2 preface in time.",
           static_cast<double>(s.connections_timed_out()));
  e.single("hapticd_grpc_connections_evicted_total", "counter",
           "Control-plane connections closed at max_connections to make room for another host.",
           static_cast<double>(s.connections_evicted()));
  e.single("hapticd_tls_handshakes_failed_total", "counter",
           "TLS handshakes on the control plane that failed.",
           static_cast<double>(s.tls_handshakes_failed()));
  e.single("hapticd_force_faults_total", "counter",
           "Non-finite forces stopped before the device.", static_cast<double>(s.force_faults()));
  e.single("hapticd_device_faults_total", "counter",
           "Ticks whose device reading failed or was not finite.",
           static_cast<double>(s.device_faults()));
  e.single("hapticd_force_saturations_total", "counter",
           "Ticks whose force was limited to the device's maximum.",
           static_cast<double>(s.force_saturations()));
  e.single("hapticd_passivity_active_ticks_total", "counter",
           "Ticks the passivity controller added damping.",
           static_cast<double>(s.passivity_active_ticks()));
  e.single("hapticd_leases_expired_total", "counter",
           "Sessions ended because their client fell silent.", static_cast<double>(s.leases_expired()));

  // Per client: one family at a time, every client's sample in it.
  struct ClientMetric {
    const char* name;
    const char* type;
    const char* help;
    std::function<double(const v1::ClientStats&)> value;
  };
  const std::vector<ClientMetric> client_metrics = {
      {"hapticd_client_datagrams_sent_total", "counter", "State datagrams sent to the client.",
       [](const v1::ClientStats& c) { return static_cast<double>(c.datagrams_sent()); }},
      {"hapticd_client_heartbeats_total", "counter", "Heartbeats accepted from the client.",
       [](const v1::ClientStats& c) { return static_cast<double>(c.heartbeats()); }},
      {"hapticd_client_states_received_total", "counter",
       "State datagrams the client accepted, as its last heartbeat reported.",
       [](const v1::ClientStats& c) { return static_cast<double>(c.states_received()); }},
      {"hapticd_client_states_lost_total", "counter",
       "State datagrams lost on the way to the client, as its last heartbeat reported.",
       [](const v1::ClientStats& c) { return static_cast<double>(c.states_lost()); }},
      {"hapticd_client_last_heartbeat_age_seconds", "gauge",
       "How long ago the client's last heartbeat arrived (-1: none yet).",
       [](const v1::ClientStats& c) { return c.last_heartbeat_age_s(); }},
      {"hapticd_client_state_decimation", "gauge",
       "The client's subscription: a state every n-th tick (0: none).",
       [](const v1::ClientStats& c) { return static_cast<double>(c.decimation()); }},
  };
  for (const ClientMetric& metric : client_metrics) {
    e.family(metric.name, metric.type, metric.help);
    for (const v1::ClientStats& client : s.clients()) {
      e.sample(metric.name, metric.value(client), client_labels(client));
    }
  }
  e.family("hapticd_client_round_trip_seconds", "summary",
           "From a tick's stamp to the client and back, over its last 256 heartbeats (real time).");
  for (const v1::ClientStats& client : s.clients()) {
    if (client.round_trip_samples() == 0) continue;
    e.quantiles_us("hapticd_client_round_trip_seconds", client.round_trip_p50_us(),
                   client.round_trip_p99_us(), client.round_trip_p999_us(), client_labels(client));
  }
  if (s.has_federation()) federation_metrics(e, s.federation());
  return e.take();
}

}  // namespace haptic::net
