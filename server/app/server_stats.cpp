// The server's statistics (Server::stats, GetStats and the metrics endpoint's source): the loop's
// counters and lateness, the network's, each client's, and with a federation its couplings' books.
#include "app/server.hpp"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <vector>

namespace haptic::app {

namespace {

/// Nearest-rank percentile of `sorted` (ascending, not empty): q = 0.5, 0.99, 0.999.
double percentile_of(const std::vector<std::int64_t>& sorted, double q) {
  const auto rank = static_cast<std::size_t>(q * static_cast<double>(sorted.size() - 1) + 0.5);
  return static_cast<double>(sorted[std::min(rank, sorted.size() - 1)]);
}

v1::ClientStats to_proto(const net::ClientStatistics& client) {
  v1::ClientStats out;
  out.set_session_id(client.info.id);
  out.set_client_name(client.info.client_name);
  out.set_peer(client.info.peer);
  out.set_device_index(client.info.device_index);
  out.set_decimation(client.decimation);
  out.set_datagrams_sent(client.datagrams_sent);
  out.set_heartbeats(client.heartbeats);
  out.set_states_received(client.states_received);
  out.set_states_lost(client.states_lost);
  out.set_ack_window(client.ack_window);
  out.set_acknowledged_sequence(client.acknowledged_sequence);
  out.set_samples_unsent(client.samples_unsent);
  out.set_last_heartbeat_age_s(
      client.since_heartbeat ? std::chrono::duration<double>(*client.since_heartbeat).count() : -1.0);
  std::vector<std::int64_t> round_trips = client.round_trips_ns;
  out.set_round_trip_samples(static_cast<std::uint32_t>(round_trips.size()));
  if (!round_trips.empty()) {
    std::sort(round_trips.begin(), round_trips.end());
    out.set_round_trip_p50_us(percentile_of(round_trips, 0.5) / 1000.0);
    out.set_round_trip_p99_us(percentile_of(round_trips, 0.99) / 1000.0);
    out.set_round_trip_p999_us(percentile_of(round_trips, 0.999) / 1000.0);
  }
  return out;
}

}  // namespace

v1::Stats Server::stats(runtime::LatenessHistogram::Counts* lateness_bins) const {
  v1::Stats stats;
  // The lateness first, the tick count after: each sample belongs to a tick already counted (the
  // loop records it after the tick), so the count read later is never below the samples.
  const std::int64_t now_ns = runtime::monotonic_now_ns();
  const runtime::LatenessSummary lateness = lateness_bins != nullptr
                                                ? lateness_.summarize(now_ns, *lateness_bins)
                                                : lateness_.summarize(now_ns);
  stats.set_ticks(counters_.ticks.load(std::memory_order_acquire));
  const std::int64_t elapsed_ns = loop_->server_time_ns();
  if (elapsed_ns > 0) {
    stats.set_achieved_rate_hz(static_cast<double>(stats.ticks()) / (static_cast<double>(elapsed_ns) * 1e-9));
  }
  stats.set_lateness_p50_us(lateness.p50_us);
  stats.set_lateness_p99_us(lateness.p99_us);
  stats.set_lateness_p999_us(lateness.p999_us);
  stats.set_lateness_max_us(lateness.max_us);
  stats.set_lateness_samples(lateness.samples);
  stats.set_window_s(lateness.window_s);
  stats.set_overruns(counters_.overruns.load(std::memory_order_relaxed));
  stats.set_sessions(static_cast<std::uint32_t>(sessions_.size()));
  const net::SceneCounts scene = scene_->counts();
  stats.set_objects(scene.objects);
  stats.set_fields(scene.fields);
  stats.set_datagrams_sent(udp_.counters().sent.load(std::memory_order_relaxed));
  stats.set_datagrams_received(udp_.counters().received.load(std::memory_order_relaxed));
  stats.set_datagrams_dropped(udp_.counters().dropped.load(std::memory_order_relaxed));
  stats.set_heartbeats_rate_limited(udp_.counters().rate_limited.load(std::memory_order_relaxed));
  stats.set_datagrams_foreign_source(udp_.counters().foreign_source.load(std::memory_order_relaxed));
  stats.set_path_challenges_sent(udp_.counters().challenges_sent.load(std::memory_order_relaxed));
  stats.set_samples_skipped(udp_.counters().samples_skipped.load(std::memory_order_relaxed));
  stats.set_samples_missed(udp_.counters().samples_missed.load(std::memory_order_relaxed));
  stats.set_ack_stalls(udp_.counters().ack_stalls.load(std::memory_order_relaxed));
  if (listener_) {
    const net::ConnectionCounters& connections = listener_->counters();
    stats.set_connections_open(connections.open.load(std::memory_order_relaxed));
    stats.set_connections_refused(connections.refused.load(std::memory_order_relaxed));
    stats.set_connections_timed_out(connections.timed_out.load(std::memory_order_relaxed));
    stats.set_connections_evicted(connections.evicted.load(std::memory_order_relaxed));
    stats.set_tls_handshakes_failed(connections.tls_failed.load(std::memory_order_relaxed));
  }
  stats.set_force_faults(counters_.force_faults.load(std::memory_order_relaxed));
  stats.set_device_faults(counters_.device_errors.load(std::memory_order_relaxed));
  stats.set_force_saturations(counters_.force_saturations.load(std::memory_order_relaxed));
  stats.set_passivity_active_ticks(counters_.passivity_active_ticks.load(std::memory_order_relaxed));
  stats.set_leases_expired(leases_expired_.load(std::memory_order_relaxed));
  const runtime::LatenessSummary send_delay = udp_.counters().send_delay.summarize(now_ns);
  stats.set_send_delay_p50_us(send_delay.p50_us);
  stats.set_send_delay_p99_us(send_delay.p99_us);
  stats.set_send_delay_p999_us(send_delay.p999_us);
  for (const net::ClientStatistics& client : sessions_.client_statistics()) {
    *stats.add_clients() = to_proto(client);
  }
  if (relay_) federation_stats(*stats.mutable_federation());
  return stats;
}

void Server::federation_stats(v1::FederationStats& out) const {
  out.set_samples_published(relay_->published());
  out.set_samples_failed(relay_->failed());
  out.set_items_published(replicator_->published());
  out.set_items_applied(replicator_->applied());
  out.set_items_refused(replicator_->refused());
  out.set_wrenches_accepted(relay_->wrenches_accepted());
  out.set_wrenches_refused(relay_->wrenches_refused() + counters_.robot_wrenches_refused.load(std::memory_order_relaxed));
  out.set_samples_refused(relay_->samples_refused());
  out.set_energy_refused_j(relay_->energy_refused());
  out.set_sites_cut_off(relay_->sites_cut_off());
  for (std::size_t port = 0; port < ledgers_.size(); ++port) {
    for (std::size_t slot = 0; slot < runtime::kMaxRemoteTools; ++slot) {
      const runtime::CouplingBooks books = ledgers_[port]->books(slot);
      if (books.key == 0) continue;
      v1::CouplingStats& coupling = *out.add_couplings();
      coupling.set_kind(v1::CouplingStats::TOOL);
      coupling.set_port(static_cast<std::uint32_t>(port));
      coupling.set_remote(books.key);
      coupling.set_injected_j(books.injected);
      coupling.set_given_j(books.given);
      coupling.set_sent_j(books.sent);
      coupling.set_received_j(books.received);
      coupling.set_reservoir_j(books.reservoir);
    }
  }
  const runtime::LocalMassTable masses = local_masses_.load();
  for (const runtime::LocalMassCopy& copy : masses.masses) {
    for (std::size_t i = 0; copy.mass_key != 0 && i < engine::kMaxRemoteCopies; ++i) {
      if (!copy.coupled_site[i]) continue;
      v1::CouplingStats& coupling = *out.add_couplings();
      coupling.set_kind(v1::CouplingStats::MASS);
      coupling.set_remote(copy.coupled_site[i].value);
      coupling.set_mass(copy.mass_key);
      coupling.set_injected_j(copy.injected[i]);
      coupling.set_given_j(copy.given[i]);
      coupling.set_sent_j(copy.sent[i]);
      coupling.set_received_j(copy.received[i]);
      coupling.set_reservoir_j(copy.reservoir[i]);
    }
  }
}

}  // namespace haptic::app
