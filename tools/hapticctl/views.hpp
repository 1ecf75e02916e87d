#pragma once
// What hapticctl prints: plain-text tables and lines made from the SDK's types. Pure functions of
// their input, so the tests check them without a server; session ids are written as the server's
// log writes them (16 hex digits).

#include <haptic/haptic.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace hapticctl {

/// The server at a glance (GetStats): the loop, the scene, the traffic, the faults, and with a
/// federation its federation_view.
std::string status_view(const haptic::Stats& stats);

/// What crossed the network (the counts), then one line per coupling across it with its layer's
/// books at this site in mJ (keys as 16 hex digits).
std::string federation_view(const haptic::FederationStats& federation);

/// Every open session (ListSessions); `own` (hapticctl's own session) is marked.
std::string sessions_view(const std::vector<haptic::SessionSummary>& sessions, std::uint64_t own);

/// One row per client (GetStats.clients): sent, received, lost, round trip, heartbeat age.
std::string clients_view(const haptic::Stats& stats, std::uint64_t own);

/// One event as a line: server time, kind, session, item, message.
std::string event_line(const haptic::Event& event);

/// The registered scene as a table: id, owner, kind and the main dimensions of each item.
std::string scene_view(const haptic::RegisteredScene& scene);

/// Left-aligned columns separated by two spaces; the first row is the header.
std::string table(const std::vector<std::vector<std::string>>& rows);

}  // namespace hapticctl
