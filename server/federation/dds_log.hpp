#pragma once
// Cyclone DDS's own log (its errors, warnings and notes: a failed DDS Security handshake, a
// refused configuration) routed to hapticd's, with identical messages written once per 10 s and
// then counted (LogLimiter): a rogue host retrying its handshake would otherwise write two lines a
// second for as long as it tries. Distinct messages always get their first line; none is dropped
// without being counted. Cyclone's sink is the process's: one route for all its domains.
//
// Cyclone calls the sink from its own threads, never from the loop's.

#include <chrono>
#include <functional>
#include <string>

namespace haptic::federation {

enum class DdsLogLevel { kInfo, kWarning, kError };

/// Where Cyclone's lines go ("dds: <Cyclone's message>"); routes them there from now on, for every
/// domain made after this call. An empty function restores Cyclone's own sink (stderr).
void route_dds_log(std::function<void(DdsLogLevel, const std::string&)> write);

/// Writes the summaries of windows ended by `now` ("dds: … (and 37 more in 10 s)"); the
/// housekeeping thread calls it, so a flood that stops is still counted.
void flush_dds_log(std::chrono::steady_clock::time_point now);

}  // namespace haptic::federation
