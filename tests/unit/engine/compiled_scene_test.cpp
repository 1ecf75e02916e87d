// Compiled scene forces: the wall and sphere contact law, springs, fades, proxies.
#include <gtest/gtest.h>

#include <cmath>

#include "engine/scene/compiled_scene.hpp"

namespace haptic::engine {
namespace {

ObjectEntry wall(Vec3 point, Vec3 normal, double k, double b, std::int64_t fade = kNeverTick,
                 Quat R = {}) {
  ObjectSpec spec;
  spec.p_WO = point;
  spec.R_WO = R;
  spec.stiffness = k;
  spec.damping = b;
  spec.shape = HalfSpaceSpec{normal};
  return {{1, 1, fade, {}}, spec};
}

ObjectEntry sphere(Vec3 center, double radius, double k, double b,
                   std::int64_t fade = kNeverTick) {
  ObjectSpec spec;
  spec.p_WO = center;
  spec.stiffness = k;
  spec.damping = b;
  spec.shape = SphereSpec{radius};
  return {{1, 2, fade, {}}, spec};
}

FieldEntry spring(Vec3 anchor, double k, double b, double max_force,
                  std::int64_t fade = kNeverTick) {
  return {{1, 3, fade, {}}, FieldSpec{SpringToPointSpec{anchor, k, b, max_force}}};
}

CompiledScene compile(SceneDescription d) { return compile_scene(d, 50, 1); }

TEST(CompiledScene, CompileFlattensByKindAndClampsTheRamp) {
  SceneDescription d;
  d.objects.push_back(wall({0, 0, 0}, {0, 0, 1}, 1000.0, 1.0));
  d.objects.push_back(sphere({0.1, 0.2, 0.3}, 0.02, 500.0, 0.5, 7));
  d.objects.push_back(wall({0, 0, 0.1}, {0, 3.0, 4.0}, 800.0, 0.0));
  d.fields.push_back(spring({0, 0, 0.02}, 20.0, 0.5, 3.0));
  const CompiledScene scene = compile_scene(d, 0, 42);
  EXPECT_EQ(scene.removal_ramp_ticks, 1);  // a zero ramp would divide by zero
  EXPECT_EQ(scene.generation, 42u);
  ASSERT_EQ(scene.half_spaces.size(), 2u);
  ASSERT_EQ(scene.spheres.size(), 1u);
  ASSERT_EQ(scene.springs.size(), 1u);
  EXPECT_EQ(scene.half_spaces[1].normal_W.x, 0.0);  // (0, 3, 4) normalised
  EXPECT_DOUBLE_EQ(scene.half_spaces[1].normal_W.y, 0.6);
  EXPECT_DOUBLE_EQ(scene.half_spaces[1].normal_W.z, 0.8);
  EXPECT_EQ(scene.half_spaces[1].point_W, (Vec3{0.0, 0.0, 0.1}));
  EXPECT_EQ(scene.spheres[0].center_W, (Vec3{0.1, 0.2, 0.3}));
  EXPECT_EQ(scene.spheres[0].radius, 0.02);
  EXPECT_EQ(scene.spheres[0].ramp.fade_begin_tick, 7);
  EXPECT_EQ(scene.springs[0].max_force, 3.0);
  EXPECT_EQ(compile_scene(d, 80, 1).removal_ramp_ticks, 80);
}

TEST(ItemRamp, VersionsOfAnItemCrossFadeWithGainsThatSumToOne) {
  constexpr std::int64_t kRamp = 50;
  // v1 always there; v2 appears at 100, v3 at 120 (faster than the ramp), v4 at 130.
  ItemRamp v1, v2, v3, v4;
  v1.superseded_at = {100, 120, 130};
  v2.appear_tick = 100;
  v2.superseded_at = {120, 130, kNeverTick};
  v3.appear_tick = 120;
  v3.superseded_at = {130, kNeverTick, kNeverTick};
  v4.appear_tick = 130;
  double previous_v4 = 0.0;
  for (std::int64_t tick = 90; tick < 200; ++tick) {
    const double g1 = ramp_gain(v1, tick, kRamp), g2 = ramp_gain(v2, tick, kRamp);
    const double g3 = ramp_gain(v3, tick, kRamp), g4 = ramp_gain(v4, tick, kRamp);
    EXPECT_NEAR(g1 + g2 + g3 + g4, 1.0, 1e-12) << tick;
    EXPECT_GE(g4, previous_v4);  // the newest only grows
    previous_v4 = g4;
  }
  EXPECT_EQ(ramp_gain(v1, 99, kRamp), 1.0);
  EXPECT_EQ(ramp_gain(v4, 180, kRamp), 1.0);
  EXPECT_EQ(ramp_gain(v4, 130, kRamp), 0.0);  // a new item starts from zero
  EXPECT_NEAR(ramp_gain(v4, 131, kRamp), 1.0 / kRamp, 1e-15);
  // Removal of the newest fades it out from wherever it is.
  v4.fade_begin_tick = 150;
  EXPECT_NEAR(ramp_gain(v4, 160, kRamp), (30.0 / kRamp) * (1.0 - 10.0 / kRamp), 1e-12);
}

TEST(CompiledScene, EmptySceneGivesNoForceAndProxyAtTheTool) {
  const CompiledScene scene = compile({});
  const SceneForce f = evaluate_scene(scene, {0.1, 0.2, 0.3}, {1, 1, 1}, 1);
  EXPECT_EQ(f.F_T_W, Vec3{});
  EXPECT_EQ(f.p_WP, (Vec3{0.1, 0.2, 0.3}));
  EXPECT_EQ(f.contact_count, 0u);
  EXPECT_FALSE(f.ramping);
}

TEST(CompiledScene, WallForceIsStiffnessTimesPenetrationAlongTheNormal) {
  const CompiledScene scene = compile({{wall({0, 0, 0}, {0, 0, 2.0}, 1000.0, 0.0)}, {}});
  ASSERT_EQ(scene.half_spaces.size(), 1u);
  EXPECT_DOUBLE_EQ(scene.half_spaces[0].normal_W.z, 1.0);  // normalised
  const SceneForce f = evaluate_scene(scene, {0.01, 0.0, -0.003}, {}, 1);
  EXPECT_DOUBLE_EQ(f.F_T_W.z, 3.0);
  EXPECT_EQ(f.F_T_W.x, 0.0);
  EXPECT_EQ(f.contact_count, 1u);
  EXPECT_EQ(f.p_WP, (Vec3{0.01, 0.0, 0.0}));
  EXPECT_EQ(evaluate_scene(scene, {0, 0, 0.001}, {}, 1).F_T_W, Vec3{});  // outside
}

TEST(CompiledScene, WallDampingOpposesNormalVelocityButNeverPulls) {
  const CompiledScene scene = compile({{wall({0, 0, 0}, {0, 0, 1}, 1000.0, 2.0)}, {}});
  // Moving in at 0.5 m/s at 1 mm: 1 N spring + 1 N damper.
  EXPECT_DOUBLE_EQ(evaluate_scene(scene, {0, 0, -0.001}, {0, 0, -0.5}, 1).F_T_W.z, 2.0);
  // Moving out at 0.25 m/s: 1 N − 0.5 N.
  EXPECT_DOUBLE_EQ(evaluate_scene(scene, {0, 0, -0.001}, {0, 0, 0.25}, 1).F_T_W.z, 0.5);
  // Moving out fast: the damper would pull the tool back in; the wall gives zero instead, though
  // the tool is still inside (a contact, with its proxy on the surface).
  const SceneForce fast_out = evaluate_scene(scene, {0, 0, -0.001}, {0, 0, 5.0}, 1);
  EXPECT_EQ(fast_out.F_T_W, Vec3{});
  EXPECT_EQ(fast_out.contact_count, 1u);
  EXPECT_EQ(fast_out.p_WP, Vec3{});
  // Tangential velocity does not enter the law.
  EXPECT_DOUBLE_EQ(evaluate_scene(scene, {0, 0, -0.001}, {3.0, -2.0, 0.0}, 1).F_T_W.z, 1.0);
}

TEST(CompiledScene, RotatedWallUsesTheRotatedNormal) {
  // 90° about x turns the object's +z normal into −y in W.
  const double s = std::sqrt(0.5);
  const CompiledScene scene =
      compile({{wall({0, 0.05, 0}, {0, 0, 1}, 500.0, 0.0, kNeverTick, Quat{s, s, 0, 0})}, {}});
  EXPECT_NEAR(scene.half_spaces[0].normal_W.y, -1.0, 1e-15);
  const SceneForce f = evaluate_scene(scene, {0, 0.06, 0}, {}, 1);  // 1 cm inside
  EXPECT_NEAR(f.F_T_W.y, -5.0, 1e-12);
  EXPECT_NEAR(f.F_T_W.z, 0.0, 1e-12);
  EXPECT_NEAR(f.p_WP.y, 0.05, 1e-15);
  EXPECT_EQ(evaluate_scene(scene, {0, 0.04, 0}, {}, 1).contact_count, 0u);  // on the open side
  // 90° about z turns an object +x normal into +y; 120° about (1,1,1) cycles x → y → z.
  const CompiledScene about_z =
      compile({{wall({0, 0, 0}, {1, 0, 0}, 500.0, 0.0, kNeverTick, Quat{s, 0, 0, s})}, {}});
  EXPECT_NEAR(about_z.half_spaces[0].normal_W.y, 1.0, 1e-15);
  EXPECT_NEAR(about_z.half_spaces[0].normal_W.x, 0.0, 1e-15);
  const CompiledScene cycled =
      compile({{wall({0, 0, 0}, {1, 0, 0}, 500.0, 0.0, kNeverTick, Quat{0.5, 0.5, 0.5, 0.5})}, {}});
  EXPECT_NEAR(cycled.half_spaces[0].normal_W.y, 1.0, 1e-15);
  EXPECT_NEAR(norm(cycled.half_spaces[0].normal_W), 1.0, 1e-15);
}

TEST(CompiledScene, SpherePushesRadiallyAndPutsTheProxyOnItsSurface) {
  const CompiledScene scene = compile({{sphere({0.1, 0, 0}, 0.02, 1000.0, 0.0)}, {}});
  const SceneForce f = evaluate_scene(scene, {0.1, 0.015, 0}, {}, 1);  // 5 mm deep, above centre
  EXPECT_NEAR(f.F_T_W.y, 5.0, 1e-12);
  EXPECT_NEAR(f.F_T_W.x, 0.0, 1e-12);
  EXPECT_NEAR(f.p_WP.y, 0.02, 1e-15);
  EXPECT_EQ(f.contact_count, 1u);
  // At the exact centre the push is along +z, with the full radius as penetration.
  const SceneForce centre = evaluate_scene(scene, {0.1, 0, 0}, {}, 1);
  EXPECT_NEAR(centre.F_T_W.z, 20.0, 1e-12);
  EXPECT_EQ(centre.p_WP, (Vec3{0.1, 0.0, 0.02}));
  // Outside: nothing, and the proxy is the tool.
  const SceneForce outside = evaluate_scene(scene, {0.1, 0.021, 0}, {}, 1);
  EXPECT_EQ(outside.F_T_W, Vec3{});
  EXPECT_EQ(outside.p_WP, (Vec3{0.1, 0.021, 0}));
  EXPECT_EQ(outside.contact_count, 0u);
}

TEST(CompiledScene, SphereDampingOpposesRadialVelocityButNeverPulls) {
  const CompiledScene scene = compile({{sphere({0, 0, 0}, 0.02, 1000.0, 2.0)}, {}});
  const Vec3 p{0.0, 0.0, 0.019};  // 1 mm deep at the north pole: 1 N from the spring
  EXPECT_NEAR(evaluate_scene(scene, p, {0, 0, -0.5}, 1).F_T_W.z, 2.0, 1e-12);  // moving in
  EXPECT_NEAR(evaluate_scene(scene, p, {0, 0, 0.25}, 1).F_T_W.z, 0.5, 1e-12);  // moving out
  EXPECT_EQ(evaluate_scene(scene, p, {0, 0, 5.0}, 1).F_T_W, Vec3{});
}

TEST(CompiledScene, SpringFieldIsMinusGradientOfItsPotentialAndClips) {
  SceneDescription d;
  d.fields.push_back(spring({0, 0, 0.02}, 20.0, 0.5, 0.0));
  const SceneForce f = evaluate_scene(compile(d), {0.01, 0, 0.02}, {0, 0.1, 0}, 1);
  EXPECT_DOUBLE_EQ(f.F_T_W.x, -0.2);
  EXPECT_DOUBLE_EQ(f.F_T_W.y, -0.05);
  EXPECT_EQ(f.contact_count, 0u);
  d.fields[0].spec = FieldSpec{SpringToPointSpec{{0, 0, 0}, 1000.0, 0.0, 2.0}};
  const SceneForce clipped = evaluate_scene(compile(d), {0.03, 0.04, 0}, {}, 1);  // 50 N unclipped
  EXPECT_NEAR(clipped.F_T_W.x, -1.2, 1e-12);  // 2 N along −(0.6, 0.8): direction kept
  EXPECT_NEAR(clipped.F_T_W.y, -1.6, 1e-12);
  EXPECT_EQ(clipped.p_WP, (Vec3{0.03, 0.04, 0}));  // a field is not a contact
  // Below the clip the law is untouched.
  EXPECT_DOUBLE_EQ(evaluate_scene(compile(d), {0.001, 0, 0}, {}, 1).F_T_W.x, -1.0);
}

TEST(CompiledScene, FadeGainIsLinearOverTheRamp) {
  EXPECT_EQ(fade_gain(kNeverTick, 5, 50), 1.0);
  EXPECT_EQ(fade_gain(kNeverTick, kNeverTick - 1, 50), 1.0);
  EXPECT_DOUBLE_EQ(fade_gain(100, 101, 50), 0.98);
  EXPECT_EQ(fade_gain(100, 99, 50), 1.0);
  EXPECT_EQ(fade_gain(100, 100, 50), 1.0);
  EXPECT_EQ(fade_gain(100, 125, 50), 0.5);
  EXPECT_EQ(fade_gain(100, 150, 50), 0.0);
  EXPECT_EQ(fade_gain(100, 1000, 50), 0.0);
}

TEST(CompiledScene, FadingWallGivesExactlyHalfAtMidRampAndCountsAsRamping) {
  const CompiledScene scene = compile({{wall({0, 0, 0}, {0, 0, 1}, 1000.0, 0.0, 100)}, {}});
  const SceneForce mid = evaluate_scene(scene, {0, 0, -0.002}, {}, 125);
  EXPECT_DOUBLE_EQ(mid.F_T_W.z, 1.0);
  EXPECT_TRUE(mid.ramping);
  const SceneForce gone = evaluate_scene(scene, {0, 0, -0.002}, {}, 150);
  EXPECT_EQ(gone.F_T_W.z, 0.0);
  EXPECT_EQ(gone.contact_count, 0u);
  EXPECT_EQ(gone.p_WP, (Vec3{0, 0, -0.002}));  // a faded wall owns no proxy
  // Its last ramping tick is the one before its force reaches zero: the flag follows the tick,
  // not when housekeeping drops the finished wall (so a lockstep run flags the same ticks).
  EXPECT_TRUE(evaluate_scene(scene, {0, 0, -0.002}, {}, 149).ramping);
  EXPECT_FALSE(gone.ramping);
  // Before its fade begins, the same wall is at full strength.
  EXPECT_DOUBLE_EQ(evaluate_scene(scene, {0, 0, -0.002}, {}, 99).F_T_W.z, 2.0);
}

TEST(CompiledScene, EveryKindFadesByExactlyHalfAtMidRamp) {
  SceneDescription d;
  d.objects.push_back(sphere({0, 0, 0}, 0.02, 1000.0, 0.0, 200));
  d.fields.push_back(spring({0.1, 0, 0}, 100.0, 0.0, 0.0, 200));
  const CompiledScene scene = compile_scene(d, 10, 1);
  const Vec3 p{0.0, 0.0, 0.016};  // 4 mm into the sphere: 4 N; spring: (10, 0, −1.6) N
  const SceneForce full = evaluate_scene(scene, p, {}, 199);
  const SceneForce half = evaluate_scene(scene, p, {}, 205);
  EXPECT_EQ(half.F_T_W, 0.5 * full.F_T_W);
  EXPECT_EQ(half.contact_count, 1u);
  EXPECT_TRUE(half.ramping);
  EXPECT_TRUE(full.ramping);  // scheduled to fade counts as ramping already
  const SceneForce gone = evaluate_scene(scene, p, {}, 210);
  EXPECT_EQ(gone.F_T_W, Vec3{});
  EXPECT_EQ(gone.contact_count, 0u);
}

TEST(CompiledScene, ContributionsAddAndTheDeepestContactOwnsTheProxy) {
  SceneDescription d;
  d.objects.push_back(wall({0, 0, 0}, {0, 0, 1}, 1000.0, 0.0));
  d.objects.push_back(wall({0, 0, 0}, {1, 0, 0}, 1000.0, 0.0));
  const SceneForce f = evaluate_scene(compile(d), {-0.003, 0, -0.001}, {}, 1);
  EXPECT_DOUBLE_EQ(f.F_T_W.x, 3.0);
  EXPECT_DOUBLE_EQ(f.F_T_W.z, 1.0);
  EXPECT_EQ(f.contact_count, 2u);
  EXPECT_EQ(f.p_WP, (Vec3{0.0, 0.0, -0.001}));  // the x wall is 3 mm deep, the z wall 1 mm
  EXPECT_FALSE(f.ramping);
  // A sphere deeper than both walls takes the proxy over.
  d.objects.push_back(sphere({-0.003, 0, -0.011}, 0.015, 100.0, 0.0));  // 5 mm deep along +z
  const SceneForce g = evaluate_scene(compile(d), {-0.003, 0, -0.001}, {}, 1);
  EXPECT_EQ(g.contact_count, 3u);
  EXPECT_NEAR(g.F_T_W.z, 1.0 + 0.5, 1e-12);
  EXPECT_NEAR(g.p_WP.z, 0.004, 1e-15);
}

}  // namespace
}  // namespace haptic::engine
