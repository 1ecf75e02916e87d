#pragma once
// hapticd --replay FILE: runs a recording's changes again, in lockstep, on a server built from the
// recorded configuration, and compares every tick's force (and position) with the recorded one,
// bit for bit. The changes go through the control plane as the clients sent them (one replay
// session per recorded session, over loopback gRPC), each after the tick it followed; so a replay
// also shows that the same calls give the same run.

#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>

namespace haptic::app {

/// A recording that cannot be replayed: not a recording, damaged, begun mid-run, or a change the
/// server refused this time. The message says which and where.
struct ReplayError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct ReplayReport {
  std::uint64_t ticks = 0;              // ticks run
  std::uint64_t changes = 0;            // recorded changes applied
  std::uint64_t samples_compared = 0;   // recorded samples found in the replay and compared
  std::uint64_t samples_differing = 0;  // of those, force or position not bit for bit the same
  std::uint64_t samples_missed = 0;     // the recording's own gaps (its end record says)
  std::uint64_t samples_not_replayed = 0;  // recorded after the replay's shutdown ramp had ended
  bool real_time = false;               // recorded in real time: changes were not tick-exact
  std::string first_difference;         // "tick 812 port 0: force x recorded … replayed …"
  std::string stopped_because;          // the recording's end record
  bool identical() const {
    return samples_differing == 0 && samples_not_replayed == 0 && samples_compared > 0;
  }
};

/// Replays the recording at `path`. `progress` (may be empty) hears the ticks run so far now and
/// then. Throws ReplayError.
ReplayReport replay_recording(const std::string& path,
                              const std::function<void(std::uint64_t ticks)>& progress = {});

}  // namespace haptic::app
