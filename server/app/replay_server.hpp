#pragma once
// The server a replay runs on (hapticd --replay): app::Server, started from the recording's
// configuration, as recording::ReplayServer.

#include "recording/replay.hpp"

namespace haptic::app {

/// Validates with config::validate and starts an app::Server.
recording::ReplayServers replay_servers();

}  // namespace haptic::app
