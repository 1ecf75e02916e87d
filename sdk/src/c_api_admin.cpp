// The C API (haptic/haptic_c.h): administration (sessions, their reports and the server's).
#include "c_api_internal.hpp"

using namespace haptic::c_api;  // this library's own helpers, for its C entry points

extern "C" {

// ---- administration ----

int haptic_client_sessions(haptic_client* client, haptic_session_summary* out, uint32_t capacity,
                           uint32_t* count, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "ListSessions", "client");
    copy_list(client->client.sessions(), out, capacity, count, "ListSessions",
              [](const haptic::SessionSummary& s) {
                haptic_session_summary c{};
                c.session_id = s.session_id;
                copy_text(c.client_name, sizeof(c.client_name), s.client_name);
                copy_text(c.peer, sizeof(c.peer), s.peer);
                copy_text(c.token_name, sizeof(c.token_name), s.token_name);
                c.device_index = s.device_index;
                c.role = static_cast<int32_t>(s.role);
                c.opened_time = s.opened_time;
                return c;
              });
    return HAPTIC_OK;
  });
}

int haptic_client_kick_session(haptic_client* client, uint64_t session_id, const char* reason,
                               haptic_error* err) {
  return guarded(err, [&] {
    require(client, "KickSession", "client");
    client->client.kick_session(session_id, text_or_empty(reason));
    return HAPTIC_OK;
  });
}

void haptic_session_id_text(uint64_t session_id, char out[17]) {
  if (out == nullptr) return;
  try {
    copy_text(out, 17, haptic::session_id_text(session_id));
  } catch (...) {
    out[0] = '\0';
  }
}

int haptic_client_stats(haptic_client* client, haptic_stats* out, haptic_stream_stats* clients,
                        uint32_t clients_capacity, haptic_coupling_stats* couplings,
                        uint32_t couplings_capacity, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "GetStats", "client");
    SizedOut<haptic_stats> written(out, "GetStats", "out");
    auto& c = *written;
    if (clients_capacity > 0) require(clients, "GetStats", "clients");
    if (couplings_capacity > 0) require(couplings, "GetStats", "couplings");
    const haptic::Stats s = client->client.stats();
    const std::uint32_t size = c.size;
    c = haptic_stats{};
    c.size = size;
    c.sessions = s.sessions;
    c.ticks = s.ticks;
    c.achieved_rate_hz = s.achieved_rate_hz;
    c.lateness_p50_us = s.lateness_p50_us;
    c.lateness_p99_us = s.lateness_p99_us;
    c.lateness_p999_us = s.lateness_p999_us;
    c.lateness_max_us = s.lateness_max_us;
    c.lateness_samples = s.lateness_samples;
    c.window_s = s.window_s;
    c.overruns = s.overruns;
    c.objects = s.objects;
    c.fields = s.fields;
    c.datagrams_sent = s.datagrams_sent;
    c.datagrams_received = s.datagrams_received;
    c.datagrams_dropped = s.datagrams_dropped;
    c.force_faults = s.force_faults;
    c.force_saturations = s.force_saturations;
    c.passivity_active_ticks = s.passivity_active_ticks;
    c.leases_expired = s.leases_expired;
    c.device_faults = s.device_faults;
    c.send_delay_p50_us = s.send_delay_p50_us;
    c.send_delay_p99_us = s.send_delay_p99_us;
    c.send_delay_p999_us = s.send_delay_p999_us;
    c.heartbeats_rate_limited = s.heartbeats_rate_limited;
    c.datagrams_foreign_source = s.datagrams_foreign_source;
    c.path_challenges_sent = s.path_challenges_sent;
    c.samples_skipped = s.samples_skipped;
    c.connections_refused = s.connections_refused;
    c.connections_timed_out = s.connections_timed_out;
    c.connections_evicted = s.connections_evicted;
    c.tls_handshakes_failed = s.tls_handshakes_failed;
    c.connections_open = s.connections_open;
    c.client_count = static_cast<uint32_t>(s.clients.size());
    for (std::size_t i = 0; i < std::min<std::size_t>(clients_capacity, s.clients.size()); ++i) {
      const haptic::ClientStats& k = s.clients[i];
      haptic_stream_stats& o = clients[i];
      o = haptic_stream_stats{};
      o.session_id = k.session_id;
      copy_text(o.client_name, sizeof(o.client_name), k.client_name);
      copy_text(o.peer, sizeof(o.peer), k.peer);
      o.device_index = k.device_index;
      o.decimation = k.decimation;
      o.datagrams_sent = k.datagrams_sent;
      o.heartbeats = k.heartbeats;
      o.states_received = k.states_received;
      o.states_lost = k.states_lost;
      o.last_heartbeat_age_s = k.last_heartbeat_age_s;
      o.round_trip_samples = k.round_trip_samples;
      o.round_trip_p50_us = k.round_trip_p50_us;
      o.round_trip_p99_us = k.round_trip_p99_us;
      o.round_trip_p999_us = k.round_trip_p999_us;
    }
    if (s.federation) {
      const haptic::FederationStats& f = *s.federation;
      c.has_federation = 1;
      c.coupling_count = static_cast<uint32_t>(f.couplings.size());
      c.federation_samples_published = f.samples_published;
      c.federation_samples_failed = f.samples_failed;
      c.federation_items_published = f.items_published;
      c.federation_items_applied = f.items_applied;
      c.federation_items_refused = f.items_refused;
      c.federation_wrenches_accepted = f.wrenches_accepted;
      c.federation_wrenches_refused = f.wrenches_refused;
      for (std::size_t i = 0; i < std::min<std::size_t>(couplings_capacity, f.couplings.size()); ++i) {
        const haptic::CouplingStats& k = f.couplings[i];
        couplings[i] = haptic_coupling_stats{static_cast<int32_t>(k.kind), k.port, k.remote, k.mass,
                                             k.injected_j, k.given_j, k.sent_j, k.received_j,
                                             k.reservoir_j};
      }
    }
    return HAPTIC_OK;
  });
}

int haptic_client_start_recording(haptic_client* client, const char* name,
                                  haptic_recording_status* out, haptic_error* err) {
  return guarded(err, [&] {
    require(client, "StartRecording", "client");
    require(name, "StartRecording", "name");
    if (out != nullptr) sized<haptic_recording_status>(out, "StartRecording", "out");
    copy_recording(client->client.start_recording(name), out);
    return HAPTIC_OK;
  });
}

int haptic_client_stop_recording(haptic_client* client, haptic_recording_status* out,
                                 haptic_error* err) {
  return guarded(err, [&] {
    require(client, "StopRecording", "client");
    if (out != nullptr) sized<haptic_recording_status>(out, "StopRecording", "out");
    copy_recording(client->client.stop_recording(), out);
    return HAPTIC_OK;
  });
}


}  // extern "C"
