#pragma once
// A token bucket: `rate` tokens a second, holding at most `burst`; each admitted event spends one.
// Used for a session's heartbeats and for a host's session openings.

#include <algorithm>
#include <chrono>

namespace haptic::net {

struct TokenBucket {
  double tokens;                                // starts full: pass the burst
  std::chrono::steady_clock::time_point at{};   // when `tokens` was last brought up to date

  /// Refills for the time since the last call and spends a token if there is one; false (nothing
  /// spent) when the bucket is empty.
  bool take(double rate_hz, double burst, std::chrono::steady_clock::time_point now) {
    const double elapsed_s = std::chrono::duration<double>(now - at).count();
    tokens = std::min(burst, tokens + std::max(0.0, elapsed_s) * rate_hz);
    at = now;
    if (tokens < 1.0) return false;
    tokens -= 1.0;
    return true;
  }
};

}  // namespace haptic::net
