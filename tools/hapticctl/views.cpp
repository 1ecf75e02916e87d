#include "views.hpp"

#include <algorithm>
#include <cstdio>
#include <sstream>
#include <type_traits>
#include <variant>

namespace hapticctl {
namespace {

std::string fixed(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  return text;
}

std::string vec(const haptic::Vec3& v) {
  return "(" + fixed(v.x, 3) + ", " + fixed(v.y, 3) + ", " + fixed(v.z, 3) + ")";
}

const char* role_name(haptic::Role role) {
  switch (role) {
    case haptic::Role::kObserver: return "observer";
    case haptic::Role::kController: return "controller";
    case haptic::Role::kAdmin: return "admin";
    case haptic::Role::kNone: break;
  }
  return "-";
}

const char* kind_name(haptic::Event::Kind kind) {
  using Kind = haptic::Event::Kind;
  switch (kind) {
    case Kind::kSessionOpened: return "SESSION_OPENED";
    case Kind::kSessionClosed: return "SESSION_CLOSED";
    case Kind::kLeaseExpired: return "LEASE_EXPIRED";
    case Kind::kSceneChanged: return "SCENE_CHANGED";
    case Kind::kForceFault: return "FORCE_FAULT";
    case Kind::kWatchStarted: return "WATCH_STARTED";
    case Kind::kDeviceFault: return "DEVICE_FAULT";
    case Kind::kReset: return "RESET";
    case Kind::kUnknown: break;
  }
  return "UNKNOWN";
}

/// "wall at (x, y, z) normal (…)", "sphere r 5.0 mm at …": what the item is, in a few words.
std::string describe(const haptic::SceneSpec::Object& object) {
  return std::visit(
      [](const auto& spec) -> std::string {
        using T = std::decay_t<decltype(spec)>;
        const std::string k = " K " + fixed(spec.impedance.stiffness, 0) + " N/m";
        if constexpr (std::is_same_v<T, haptic::WallSpec>) {
          return "wall at " + vec(spec.point) + " normal " + vec(spec.normal) + k;
        } else if constexpr (std::is_same_v<T, haptic::SphereSpec>) {
          return "sphere r " + fixed(spec.radius * 1e3, 1) + " mm at " + vec(spec.center) + k;
        } else if constexpr (std::is_same_v<T, haptic::BoxSpec>) {
          return "box half " + vec(spec.half_extents) + " at " + vec(spec.pose.position) + k;
        } else if constexpr (std::is_same_v<T, haptic::CapsuleSpec>) {
          return "capsule at " + vec(spec.pose.position) + k;
        } else if constexpr (std::is_same_v<T, haptic::TangentPlaneSpec>) {
          return "tangent plane" + k;
        } else {
          return "mesh of " + std::to_string(spec.indices.size() / 3) + " triangles at " +
                 vec(spec.pose.position) + k;
        }
      },
      object);
}

std::string describe(const haptic::SceneSpec::Field& field) {
  return std::visit(
      [](const auto& spec) -> std::string {
        using T = std::decay_t<decltype(spec)>;
        if constexpr (std::is_same_v<T, haptic::SpringFieldSpec>) return "spring field";
        else if constexpr (std::is_same_v<T, haptic::DistanceSpringSpec>) return "distance spring";
        else if constexpr (std::is_same_v<T, haptic::PotentialFieldSpec>) return "potential field";
        else if constexpr (std::is_same_v<T, haptic::LinearFieldSpec>) return "linear field";
        else if constexpr (std::is_same_v<T, haptic::ViscousFieldSpec>) return "viscous field";
        else if constexpr (std::is_same_v<T, haptic::OrientationSpringSpec>) return "orientation spring";
        else if constexpr (std::is_same_v<T, haptic::OrientationDetentSpec>) return "orientation detent";
        else return "detent field";
      },
      field);
}

/// A site's, tool's or mass's key of a federation, written as a session id is (16 hex digits).
std::string key_text(std::uint64_t key) { return haptic::session_id_text(key); }

std::string owner_text(std::uint64_t session) { return session == 0 ? "server" : haptic::session_id_text(session); }

}  // namespace

std::string table(const std::vector<std::vector<std::string>>& rows) {
  std::vector<std::size_t> widths;
  for (const auto& row : rows) {
    widths.resize(std::max(widths.size(), row.size()), 0);
    for (std::size_t c = 0; c < row.size(); ++c) widths[c] = std::max(widths[c], row[c].size());
  }
  std::string out;
  for (const auto& row : rows) {
    std::string line;
    for (std::size_t c = 0; c < row.size(); ++c) {
      line += row[c];
      if (c + 1 < row.size()) line += std::string(widths[c] - row[c].size() + 2, ' ');
    }
    out += line + "\n";
  }
  return out;
}

std::string status_view(const haptic::Stats& s) {
  std::ostringstream out;
  out << "loop      " << s.ticks << " ticks at " << fixed(s.achieved_rate_hz, 1) << " Hz, "
      << s.overruns << " overruns\n"
      << "lateness  p50 " << fixed(s.lateness_p50_us, 0) << " us  p99 " << fixed(s.lateness_p99_us, 0)
      << " us  p99.9 " << fixed(s.lateness_p999_us, 0) << " us  max " << fixed(s.lateness_max_us, 0)
      << " us  (last " << fixed(s.window_s, 0) << " s, " << s.lateness_samples << " ticks)\n"
      << "send      p50 " << fixed(s.send_delay_p50_us, 0) << " us  p99 "
      << fixed(s.send_delay_p99_us, 0) << " us  p99.9 " << fixed(s.send_delay_p999_us, 0)
      << " us  (tick stamp to datagram out)\n"
      << "sessions  " << s.sessions << " open, " << s.leases_expired << " leases expired\n"
      << "scene     " << s.objects << " objects, " << s.fields << " fields\n"
      << "udp       " << s.datagrams_sent << " sent, " << s.datagrams_received << " received, "
      << s.datagrams_dropped << " dropped (" << s.heartbeats_rate_limited << " over budget, "
      << s.datagrams_foreign_source << " foreign), " << s.samples_skipped << " samples skipped\n"
      << "grpc      " << s.connections_open << " connections, " << s.connections_refused
      << " refused, " << s.connections_timed_out << " timed out, " << s.connections_evicted
      << " evicted, " << s.tls_handshakes_failed << " TLS handshakes failed\n"
      << "faults    " << s.force_faults << " force, " << s.device_faults << " device, "
      << s.force_saturations << " saturated ticks, " << s.passivity_active_ticks
      << " passivity ticks\n";
  if (s.federation) out << federation_view(*s.federation);
  return out.str();
}

std::string federation_view(const haptic::FederationStats& f) {
  std::ostringstream out;
  out << "federation  " << f.samples_published << " samples published, " << f.samples_failed
      << " failed; items " << f.items_published << " published, " << f.items_applied
      << " applied, " << f.items_refused << " refused; wrenches " << f.wrenches_accepted
      << " accepted, " << f.wrenches_refused << " refused\n";
  if (f.samples_refused + f.sites_cut_off > 0 || f.energy_refused_j > 0.0) {
    out << "  from other sites: " << f.samples_refused << " samples refused, " << fixed(f.energy_refused_j * 1e3, 3)
        << " mJ claimed and not credited, " << f.sites_cut_off << " sites cut off\n";
  }
  if (f.couplings.empty()) out << "  no coupling across the network\n";
  const auto mj = [](double joules) { return fixed(joules * 1e3, 3) + " mJ"; };
  for (const haptic::CouplingStats& c : f.couplings) {
    if (c.kind == haptic::CouplingStats::Kind::kMass) {
      out << "  mass " << key_text(c.mass) << " with site " << key_text(c.remote);
    } else {
      out << "  tool port " << c.port << " with tool " << key_text(c.remote);
    }
    out << ": injected " << mj(c.injected_j) << ", given " << mj(c.given_j) << ", sent "
        << mj(c.sent_j) << ", received " << mj(c.received_j) << ", held " << mj(c.reservoir_j)
        << "\n";
  }
  return out.str();
}

std::string sessions_view(const std::vector<haptic::SessionSummary>& sessions, std::uint64_t own) {
  std::vector<std::vector<std::string>> rows = {
      {"SESSION", "CLIENT", "DEVICE", "PEER", "TOKEN", "ROLE", "OPENED_S"}};
  for (const haptic::SessionSummary& s : sessions) {
    rows.push_back({haptic::session_id_text(s.session_id) + (s.session_id == own ? "*" : ""), s.client_name,
                    std::to_string(s.device_index), s.peer.empty() ? "-" : s.peer,
                    s.token_name.empty() ? "-" : s.token_name, role_name(s.role),
                    fixed(s.opened_time, 3)});
  }
  return table(rows) + "(* this hapticctl)\n";
}

std::string clients_view(const haptic::Stats& stats, std::uint64_t own) {
  std::vector<std::vector<std::string>> rows = {{"SESSION", "CLIENT", "PEER", "DEC", "SENT",
                                                 "RECEIVED", "LOST", "LOSS%", "RTT_P50_MS",
                                                 "RTT_P99_MS", "RTT_P999_MS", "HB_AGE_S"}};
  for (const haptic::ClientStats& c : stats.clients) {
    const std::uint64_t reported = c.states_received + c.states_lost;
    const bool rtt = c.round_trip_samples > 0;
    rows.push_back({haptic::session_id_text(c.session_id) + (c.session_id == own ? "*" : ""), c.client_name,
                    c.peer.empty() ? "-" : c.peer,
                    c.decimation == 0 ? "-" : std::to_string(c.decimation),
                    std::to_string(c.datagrams_sent), std::to_string(c.states_received),
                    std::to_string(c.states_lost),
                    reported == 0 ? "-" : fixed(100.0 * static_cast<double>(c.states_lost) /
                                                    static_cast<double>(reported), 2),
                    rtt ? fixed(c.round_trip_p50_us / 1e3, 3) : "-",
                    rtt ? fixed(c.round_trip_p99_us / 1e3, 3) : "-",
                    rtt ? fixed(c.round_trip_p999_us / 1e3, 3) : "-",
                    c.last_heartbeat_age_s < 0.0 ? "-" : fixed(c.last_heartbeat_age_s, 2)});
  }
  return table(rows);
}

std::string event_line(const haptic::Event& event) {
  std::string line = fixed(event.server_time, 3) + "  " + kind_name(event.kind) + "  " +
                     (event.session_id == 0 ? std::string("server") : haptic::session_id_text(event.session_id));
  if (!event.message.empty()) line += "  " + event.message;
  return line;
}

std::string scene_view(const haptic::RegisteredScene& scene) {
  std::vector<std::vector<std::string>> rows = {{"KIND", "ID", "SESSION", "WHAT"}};
  for (std::size_t i = 0; i < scene.scene.objects.size(); ++i) {
    rows.push_back({"object", std::to_string(scene.object_ids[i]), owner_text(scene.object_sessions[i]),
                    describe(scene.scene.objects[i])});
  }
  for (std::size_t i = 0; i < scene.scene.fields.size(); ++i) {
    rows.push_back({"field", std::to_string(scene.field_ids[i]), owner_text(scene.field_sessions[i]),
                    describe(scene.scene.fields[i])});
  }
  return table(rows);
}

}  // namespace hapticctl
