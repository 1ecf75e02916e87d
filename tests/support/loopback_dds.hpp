// What the federation's DDS tests on loopback share: a domain of the test process's own
// (support/dds_domain.hpp), and a bounded wait.
#pragma once

#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <thread>

#include "federation/dds_participant.hpp"
#include "support/dds_domain.hpp"

namespace haptic::test {

/// This test process's DDS domain on loopback (ctest runs tests in parallel; loopback discovery
/// would otherwise mix their samples), unicast to 127.0.0.1.
inline federation::DomainOptions loopback_domain() {
  federation::DomainOptions options;
  options.domain_id = process_dds_domain();
  options.interface = "lo";
  options.peers = {"127.0.0.1"};
  return options;
}

/// Polls `condition` every 5 ms until it holds or `limit` has passed; its last answer.
template <class Condition>
bool eventually(Condition&& condition, std::chrono::milliseconds limit = std::chrono::seconds(10)) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < deadline) {
    if (condition()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return condition();
}

}  // namespace haptic::test
