// engine::avatar_contact: another site's tool as a frictionless sphere that pushes this tool out
// and never pulls (docs/federation.md, "Avatars").
#include <gtest/gtest.h>

#include "engine/scene/avatar_contact.hpp"

namespace haptic::engine {
namespace {

constexpr double kRadius = 0.01, kK = 500.0, kB = 2.0;

TEST(AvatarContact, PushesOutAlongTheLineBetweenTheToolsWithTheSpringsEnergy) {
  // 4 mm inside a 10 mm sphere, on +x of the remote tool, both still: F = K d along +x.
  const AvatarContact c = avatar_contact({0.006, 0, 0}, {}, {0, 0, 0}, {}, kRadius, kK, kB, 1.0);
  EXPECT_NEAR(c.F_T_W.x, kK * 0.004, 1e-12);
  EXPECT_EQ(c.F_T_W.y, 0.0);
  EXPECT_EQ(c.F_T_W.z, 0.0);
  EXPECT_NEAR(c.stored_J, 0.5 * kK * 0.004 * 0.004, 1e-15);
}

TEST(AvatarContact, DampsTheRelativeVelocityAlongTheNormalOnly) {
  // Approaching at 0.1 m/s along the normal adds B·0.1; sliding along it (y) adds nothing.
  const AvatarContact in = avatar_contact({0.006, 0, 0}, {-0.1, 0.3, 0}, {0, 0, 0}, {0, 0.3, 0}, kRadius, kK, kB, 1.0);
  EXPECT_NEAR(in.F_T_W.x, kK * 0.004 + kB * 0.1, 1e-12);
  EXPECT_EQ(in.F_T_W.y, 0.0);
}

TEST(AvatarContact, NeverPullsAndIsNothingApartOrOnTopOfEachOther) {
  // Leaving fast enough that the damper outweighs the spring: zero, not a pull.
  EXPECT_EQ(avatar_contact({0.006, 0, 0}, {10.0, 0, 0}, {0, 0, 0}, {}, kRadius, kK, kB, 1.0).F_T_W.x, 0.0);
  const AvatarContact apart = avatar_contact({0.02, 0, 0}, {}, {0, 0, 0}, {}, kRadius, kK, kB, 1.0);
  EXPECT_EQ(apart.F_T_W.x, 0.0);
  EXPECT_EQ(apart.stored_J, 0.0);
  const AvatarContact same = avatar_contact({0.001, 0.002, 0.003}, {}, {0.001, 0.002, 0.003}, {}, kRadius, kK, kB, 1.0);
  EXPECT_EQ(same.F_T_W.x, 0.0);  // no direction to push in
  EXPECT_EQ(same.stored_J, 0.0);
}

TEST(AvatarContact, AFadingAvatarScalesForceAndEnergyByItsGain) {
  const AvatarContact full = avatar_contact({0, 0.005, 0}, {}, {0, 0, 0}, {}, kRadius, kK, kB, 1.0);
  const AvatarContact half = avatar_contact({0, 0.005, 0}, {}, {0, 0, 0}, {}, kRadius, kK, kB, 0.5);
  EXPECT_NEAR(half.F_T_W.y, 0.5 * full.F_T_W.y, 1e-15);
  EXPECT_NEAR(half.stored_J, 0.5 * full.stored_J, 1e-18);
}

}  // namespace
}  // namespace haptic::engine
