#pragma once
// What the SDK's integration tests share: a client configuration for a test's server, a lockstep
// step that hands back the stepped tick's sample, and a log of a client's connection changes.

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>
#include <utility>
#include <vector>

#include "haptic/haptic.hpp"
#include "integration/server_process.hpp"

namespace haptic::test {

/// A client of `server` on device port `device_index`, heartbeating every 20 ms: well inside the
/// shortest lease a test gives (300 ms), so only a test that stops them loses its session.
inline ClientConfig config_for(const ServerProcess& server, const char* name = "test",
                               std::uint32_t device_index = 0) {
  ClientConfig config;
  config.server_address = server.address();
  config.client_name = name;
  config.device_index = device_index;
  config.heartbeat_period = std::chrono::milliseconds(20);
  return config;
}

/// Steps a lockstep server `ticks` ticks and returns the last one's sample (the Step reply carries
/// it, so it always arrives).
inline State step_and_get(Client& client, std::uint32_t ticks) {
  const std::uint64_t tick = client.step(ticks);
  State state;
  EXPECT_TRUE(client.wait_for_tick(tick, state, std::chrono::seconds(5))) << "no state for tick " << tick;
  EXPECT_EQ(state.tick, tick);
  return state;
}

/// The changes a client announces, with the time each arrived. Declare it before the Client it
/// attaches to, so that it outlives the callbacks.
class ConnectionLog {
 public:
  void attach(Client& client) {
    client.on_connection([this](const ConnectionChange& change) {
      std::lock_guard lock(mutex_);
      changes_.push_back({change, std::chrono::steady_clock::now()});
      arrived_.notify_all();
    });
  }
  /// Waits up to `timeout` for the `n`-th change (1-based); its copy, or none.
  std::optional<std::pair<ConnectionChange, std::chrono::steady_clock::time_point>> wait(
      std::size_t n, std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    if (!arrived_.wait_for(lock, timeout, [&] { return changes_.size() >= n; })) return std::nullopt;
    return changes_[n - 1];
  }

 private:
  std::mutex mutex_;
  std::condition_variable arrived_;
  std::vector<std::pair<ConnectionChange, std::chrono::steady_clock::time_point>> changes_;
};

}  // namespace haptic::test
