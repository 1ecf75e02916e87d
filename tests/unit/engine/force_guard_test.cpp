// The last stage before the device: NaN/inf never pass, magnitude and rate are limited
// (libfranka's checkFinite/limitRate, in this engine's terms).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "engine/safety/force_guard.hpp"

namespace haptic::engine {
namespace {

constexpr double kDt = 0.001;  // s
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(ForceGuard, NonFiniteInAnyComponentIsAFaultAndBecomesZero) {
  for (const double bad : {kNaN, kInf, -kInf}) {
    for (int axis = 0; axis < 3; ++axis) {
      Vec3 request{1.0, 2.0, 3.0};
      (axis == 0 ? request.x : axis == 1 ? request.y : request.z) = bad;
      ForceGuard guard(ForceLimits{20.0, 0.0});
      guard.apply({1, 1, 1}, kDt);
      const GuardedForce out = guard.apply(request, kDt);
      EXPECT_TRUE(out.fault) << bad << " on axis " << axis;
      EXPECT_FALSE(out.saturated);
      EXPECT_EQ(out.F_T_W, Vec3{});
      EXPECT_EQ(guard.last(), Vec3{});
    }
  }
}

TEST(ForceGuard, FaultClearsOnTheNextFiniteRequestAndRampsFromZero) {
  ForceGuard guard(ForceLimits{20.0, 1000.0});  // 1 N per 1 ms tick
  for (int i = 0; i < 10; ++i) guard.apply({0, 0, 5.0}, kDt);
  ASSERT_EQ(guard.last(), (Vec3{0, 0, 5.0}));
  EXPECT_TRUE(guard.apply({0, 0, kNaN}, kDt).fault);
  const GuardedForce next = guard.apply({0, 0, 5.0}, kDt);
  EXPECT_FALSE(next.fault);
  EXPECT_DOUBLE_EQ(next.F_T_W.z, 1.0);  // the limiter restarts from the zero it output
}

TEST(ForceGuard, GainDoesNotHideANonFiniteRequest) {
  ForceGuard guard(ForceLimits{});
  EXPECT_TRUE(guard.apply({kInf, 0, 0}, kDt, 0.0).fault);  // inf × 0 is NaN
  EXPECT_TRUE(guard.apply({1, 0, 0}, kDt, kNaN).fault);
  // A huge but finite request times a zero gain is not a fault.
  EXPECT_FALSE(guard.apply({1e300, 0, 0}, kDt, 0.0).fault);
}

TEST(ForceGuard, SaturationScalesTheMagnitudeAndKeepsTheDirection) {
  ForceGuard guard(ForceLimits{10.0, 0.0});
  const GuardedForce out = guard.apply({30.0, -40.0, 0.0}, kDt);
  EXPECT_TRUE(out.saturated);
  EXPECT_FALSE(out.fault);
  EXPECT_NEAR(out.F_T_W.x, 6.0, 1e-12);
  EXPECT_NEAR(out.F_T_W.y, -8.0, 1e-12);
  EXPECT_EQ(out.F_T_W.z, 0.0);
  EXPECT_NEAR(norm(guard.last()), 10.0, 1e-12);
  const GuardedForce within = guard.apply({3.0, 4.0, 0.0}, kDt);
  EXPECT_FALSE(within.saturated);
  EXPECT_EQ(within.F_T_W, (Vec3{3.0, 4.0, 0.0}));  // untouched, bit for bit
  EXPECT_FALSE(guard.apply({0.0, 0.0, 10.0}, kDt).saturated);  // exactly at the limit
}

TEST(ForceGuard, RateLimitBoundsEachComponentsChangePerTick) {
  ForceGuard guard(ForceLimits{100.0, 1000.0});  // 1000 N/s × 1 ms = 1 N per tick
  GuardedForce out = guard.apply({0.5, -3.0, 5.0}, kDt);
  EXPECT_TRUE(out.saturated);
  EXPECT_DOUBLE_EQ(out.F_T_W.x, 0.5);  // within the step: untouched
  EXPECT_DOUBLE_EQ(out.F_T_W.y, -1.0);
  EXPECT_DOUBLE_EQ(out.F_T_W.z, 1.0);
  out = guard.apply({0.5, -3.0, 5.0}, kDt);
  EXPECT_DOUBLE_EQ(out.F_T_W.z, 2.0);
  for (int i = 0; i < 3; ++i) out = guard.apply({0.5, -3.0, 5.0}, kDt);
  EXPECT_EQ(out.F_T_W, (Vec3{0.5, -3.0, 5.0}));
  EXPECT_FALSE(out.saturated);
  EXPECT_DOUBLE_EQ(guard.apply({0.5, -3.0, -5.0}, kDt).F_T_W.z, 4.0);  // down as well as up
  // The step scales with dt: 2 ms allows 2 N.
  guard.reset();
  EXPECT_DOUBLE_EQ(guard.apply({0, 0, 5.0}, 2 * kDt).F_T_W.z, 2.0);
}

TEST(ForceGuard, AFullScaleStepIsSpreadOverTheRampTimeAtEveryLoopRate) {
  // A device's limits: a 20 N step must not reach the hand in one tick (it did at 20,000 N/s).
  for (const double rate_hz : {1000.0, 4000.0, 10000.0}) {
    const double dt = 1.0 / rate_hz;
    ForceGuard guard(force_limits_for(20.0));
    int ticks = 0;
    GuardedForce out;
    do {
      out = guard.apply({0, 0, 20.0}, dt);
      ++ticks;
      EXPECT_LE(out.F_T_W.z, 20.0 * ticks * dt / kFullScaleForceRampTime + 1e-9);
    } while (out.F_T_W.z < 20.0 && ticks < 1000);
    EXPECT_EQ(ticks, static_cast<int>(std::lround(kFullScaleForceRampTime * rate_hz))) << rate_hz;
    // And back down just as gradually.
    EXPECT_NEAR(guard.apply({0, 0, 0.0}, dt).F_T_W.z, 20.0 - 20.0 * dt / kFullScaleForceRampTime,
                1e-9);
  }
  EXPECT_DOUBLE_EQ(ForceLimits{}.max_force_rate, force_limits_for(20.0).max_force_rate);
}

TEST(ForceGuard, ZeroRateMeansUnlimited) {
  ForceGuard guard(ForceLimits{100.0, 0.0});
  const GuardedForce out = guard.apply({0, 0, 90.0}, kDt);
  EXPECT_FALSE(out.saturated);
  EXPECT_EQ(out.F_T_W.z, 90.0);
}

TEST(ForceGuard, RateLimitThenSaturation) {
  ForceGuard guard(ForceLimits{1.5, 2000.0});  // 2 N per tick, 1.5 N magnitude
  const GuardedForce out = guard.apply({0, 3.0, 4.0}, kDt);
  // Rate: (0, 2, 2); magnitude 2.83 → scaled to 1.5 along (0, 1, 1)/√2.
  EXPECT_TRUE(out.saturated);
  EXPECT_NEAR(out.F_T_W.y, 1.5 / std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(out.F_T_W.z, 1.5 / std::sqrt(2.0), 1e-12);
}

TEST(ForceGuard, OutputGainScalesBeforeTheLimits) {
  ForceGuard guard(ForceLimits{20.0, 0.0});
  EXPECT_DOUBLE_EQ(guard.apply({0, 0, 8.0}, kDt, 0.25).F_T_W.z, 2.0);
  // 100 N × 0.1 = 10 N, under the 20 N limit: not saturated.
  const GuardedForce scaled = guard.apply({0, 0, 100.0}, kDt, 0.1);
  EXPECT_DOUBLE_EQ(scaled.F_T_W.z, 10.0);
  EXPECT_FALSE(scaled.saturated);
  EXPECT_EQ(guard.apply({0, 0, 8.0}, kDt, 0.0).F_T_W, Vec3{});
  EXPECT_EQ(guard.last(), Vec3{});
}

}  // namespace
}  // namespace haptic::engine
