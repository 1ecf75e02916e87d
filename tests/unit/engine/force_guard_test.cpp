// The last stage before the device: NaN/inf never pass, magnitude and rate are limited.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "engine/safety/force_guard.hpp"

namespace haptic::engine {
namespace {

constexpr double kDt = 0.001;
const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

TEST(ForceGuard, NonFiniteRequestsAreFaultsAndBecomeZero) {
  for (const Vec3 bad : {Vec3{kNaN, 0, 0}, Vec3{0, kInf, 0}, Vec3{0, 0, -kInf}}) {
    ForceGuard guard(ForceLimits{20.0, 0.0});
    guard.apply({1, 1, 1}, kDt);
    const GuardedForce out = guard.apply(bad, kDt);
    EXPECT_TRUE(out.fault);
    EXPECT_EQ(out.F_T_W, Vec3{});
    EXPECT_EQ(guard.last(), Vec3{});
  }
  // A huge but finite request times a zero gain is not a fault.
  ForceGuard guard(ForceLimits{});
  EXPECT_FALSE(guard.apply({1e300, 0, 0}, kDt, 0.0).fault);
}

TEST(ForceGuard, SaturationKeepsTheDirection) {
  ForceGuard guard(ForceLimits{10.0, 0.0});
  const GuardedForce out = guard.apply({30.0, 40.0, 0.0}, kDt);
  EXPECT_TRUE(out.saturated);
  EXPECT_NEAR(out.F_T_W.x, 6.0, 1e-12);
  EXPECT_NEAR(out.F_T_W.y, 8.0, 1e-12);
  EXPECT_FALSE(guard.apply({3.0, 4.0, 0.0}, kDt).saturated);
}

TEST(ForceGuard, RateLimitBoundsTheChangePerTick) {
  ForceGuard guard(ForceLimits{100.0, 1000.0});  // 1 N per 1 ms tick
  GuardedForce out = guard.apply({0, 0, 5.0}, kDt);
  EXPECT_TRUE(out.saturated);
  EXPECT_DOUBLE_EQ(out.F_T_W.z, 1.0);
  out = guard.apply({0, 0, 5.0}, kDt);
  EXPECT_DOUBLE_EQ(out.F_T_W.z, 2.0);
  for (int i = 0; i < 3; ++i) out = guard.apply({0, 0, 5.0}, kDt);
  EXPECT_DOUBLE_EQ(out.F_T_W.z, 5.0);
  EXPECT_FALSE(out.saturated);
  EXPECT_DOUBLE_EQ(guard.apply({0, 0, -5.0}, kDt).F_T_W.z, 4.0);
}

TEST(ForceGuard, OutputGainScalesBeforeTheLimits) {
  ForceGuard guard(ForceLimits{20.0, 0.0});
  EXPECT_DOUBLE_EQ(guard.apply({0, 0, 8.0}, kDt, 0.25).F_T_W.z, 2.0);
  EXPECT_EQ(guard.apply({0, 0, 8.0}, kDt, 0.0).F_T_W, Vec3{});
}

}  // namespace
}  // namespace haptic::engine
