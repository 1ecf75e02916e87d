#pragma once
// hapticd --replay FILE: runs a recording's changes again, in lockstep, on a server built from the
// recorded configuration, and compares every tick's force (and position) with the recorded one,
// bit for bit. The changes go through the control plane as the clients sent them (one replay
// session per recorded session, over loopback gRPC), each after the tick it followed; so a replay
// also shows that the same calls give the same run.
//
// The server replayed on is the application's (app::Server, through app/replay_server.hpp): this
// folder knows it only as a ReplayServer, so the recording sits below net and app, and both use it.

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

#include "haptic/v1/config.pb.h"
#include "runtime/sample_ring.hpp"

namespace haptic::recording {

/// A started server a replay runs on: its control plane on loopback, each device port's samples.
class ReplayServer {
 public:
  virtual ~ReplayServer() = default;
  /// The control plane's port on 127.0.0.1.
  virtual std::uint16_t grpc_port() const = 0;
  virtual std::size_t device_ports() const = 0;
  /// Port `port`'s samples, as the loop publishes them.
  virtual const runtime::SampleRing& samples(std::size_t port) const = 0;
  /// The server's shutdown, its ramp of the device's force to zero included; again is nothing.
  virtual void shutdown() = 0;
};

/// How a replay gets its server. The configuration handed over is the recording's, already made to
/// replay (lockstep, loopback, ephemeral ports, no security).
struct ReplayServers {
  /// "" when `config` can be run here, else why not.
  std::function<std::string(const v1::ServerConfig& config)> validate;
  /// A started server running `config`.
  std::function<std::unique_ptr<ReplayServer>(const v1::ServerConfig& config)> start;
};

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

/// A recording cut short: no end record, because its recorder was killed (or the machine) or the
/// file ends inside a record or a compressed block. Everything up to its last whole record was
/// replayed: `report` says how that went; what() says where the recording stops (its last whole
/// record's number and tick, the byte it ends at) and why.
struct ReplayCutShort : ReplayError {
  ReplayCutShort(const std::string& what, ReplayReport replayed)
      : ReplayError(what), report(std::move(replayed)) {}
  ReplayReport report;
};

/// Replays the recording at `path`. `progress` (may be empty) hears the ticks run so far now and
/// then. Throws ReplayCutShort (a ReplayError) for a recording cut short, ReplayError for one that
/// cannot be replayed.
ReplayReport replay_recording(const std::string& path, const ReplayServers& servers,
                              const std::function<void(std::uint64_t ticks)>& progress = {});

/// hapticd --replay's exit statuses.
inline constexpr int kReplaySame = 0;      // every force and position the same, bit for bit
inline constexpr int kReplayDiffers = 1;   // any differs (the first is named)
inline constexpr int kReplayRefused = 2;   // cannot be replayed (not a recording, damaged, mid-run)
inline constexpr int kReplayCutShort = 3;  // cut short (no end record), and all that is there the same
/// hapticd --replay's help text, naming the exit statuses.
extern const char* const kReplayHelp;

/// hapticd --replay FILE: replays the recording, prints the result to `out` (what went wrong and
/// where to `err`, and the progress too when `err` is a terminal) and returns the exit status.
int replay_command(const std::string& path, const ReplayServers& servers, std::FILE* out = stdout,
                   std::FILE* err = stderr);

}  // namespace haptic::recording
