#pragma once
// What the SDK's integration tests share: a client configuration for a test's server, and a
// lockstep step that hands back the stepped tick's sample.

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>

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

}  // namespace haptic::test
