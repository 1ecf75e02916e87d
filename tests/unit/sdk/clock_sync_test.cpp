// The SDK's clock sync against a synthetic server clock that runs 50 ppm fast, with one-way
// delays drawn from 20 µs up (the least-delayed sample of each window bounds the offset).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>

#include "clock_sync.hpp"

namespace haptic::detail {
namespace {

constexpr double kDrift = 50e-6;                  // the server's clock runs 50 ppm fast
constexpr std::int64_t kBase = 7'000'000'000'000;  // local steady time at the start. Unit: ns.
constexpr std::int64_t kOffset = 123'456'789;      // server − local at the start. Unit: ns.
constexpr std::int64_t kMinDelay = 20'000;         // the quickest one-way delay. Unit: ns.

std::int64_t server_at(std::int64_t local_ns) {
  return local_ns + kOffset + static_cast<std::int64_t>(kDrift * static_cast<double>(local_ns - kBase));
}

/// Feeds `samples` States sent 1 ms apart; returns the local time of the last send.
std::int64_t feed(ClockSync& sync, int samples, std::mt19937_64& random) {
  std::exponential_distribution<double> extra(1.0 / 60'000.0);  // mean 60 µs above the minimum
  std::int64_t sent = kBase;
  for (int k = 0; k < samples; ++k) {
    sent = kBase + std::int64_t{k} * 1'000'000;
    const auto delay = kMinDelay + static_cast<std::int64_t>(extra(random));
    sync.add(server_at(sent), sent + delay);
  }
  return sent;
}

TEST(ClockSync, NothingIsKnownBeforeSamplesAndNoDriftBeforeTwoWindows) {
  ClockSync sync;
  EXPECT_FALSE(sync.offset_ns().has_value());
  EXPECT_FALSE(sync.server_ns_at(kBase).has_value());
  std::mt19937_64 random(1);
  feed(sync, static_cast<int>(ClockSync::kWindow) * 2 - 1, random);
  EXPECT_TRUE(sync.offset_ns().has_value());
  EXPECT_FALSE(sync.drift().has_value());  // one window closed
}

TEST(ClockSync, FitsTheDriftAndCarriesTheOffsetForward) {
  ClockSync sync;
  std::mt19937_64 random(42);
  const std::int64_t last = feed(sync, static_cast<int>(ClockSync::kWindow) * 20, random);  // 40 s
  ASSERT_TRUE(sync.drift().has_value());
  std::printf("  drift %.3f ppm (true 50)\n", *sync.drift() * 1e6);
  EXPECT_NEAR(*sync.drift(), kDrift, 1e-6);
  // 1.9 s after the last window closed: with the drift the estimate is the true server time less
  // about the quickest delay; the offset alone has fallen a further ~95 µs behind.
  const std::int64_t later = last + 1'900'000'000;
  const std::int64_t error = *sync.server_ns_at(later) - server_at(later);
  const std::int64_t stale = later + *sync.offset_ns() - server_at(later);
  std::printf("  at +1.9 s: error %.1f us with the drift, %.1f us with the offset alone\n",
              static_cast<double>(error) * 1e-3, static_cast<double>(stale) * 1e-3);
  EXPECT_LT(std::abs(error + kMinDelay), 10'000);  // within 10 µs of −(quickest delay)
  EXPECT_LT(stale, error - 50'000);                // the stale offset is much further off
}

TEST(ClockSync, TheAgeIsTheDelayBeyondTheQuickest) {
  ClockSync sync;
  EXPECT_EQ(sync.add(kBase + kOffset, kBase + kMinDelay), 0);          // the first sets the bar
  EXPECT_EQ(sync.add(kBase + kOffset, kBase + kMinDelay + 5'000), 5'000);  // 5 µs slower
}

}  // namespace
}  // namespace haptic::detail
