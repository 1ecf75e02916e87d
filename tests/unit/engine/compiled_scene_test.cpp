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
  return {{1, 1, fade}, spec};
}

ObjectEntry sphere(Vec3 center, double radius, double k, double b) {
  ObjectSpec spec;
  spec.p_WO = center;
  spec.stiffness = k;
  spec.damping = b;
  spec.shape = SphereSpec{radius};
  return {{1, 2, kNeverTick}, spec};
}

CompiledScene compile(SceneDescription d) { return compile_scene(d, 50, 1); }

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
  // Moving out fast: the damper would pull the tool back in; the wall gives zero instead.
  EXPECT_EQ(evaluate_scene(scene, {0, 0, -0.001}, {0, 0, 5.0}, 1).F_T_W.z, 0.0);
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
}

TEST(CompiledScene, SpherePushesRadiallyAndPutsTheProxyOnItsSurface) {
  const CompiledScene scene = compile({{sphere({0.1, 0, 0}, 0.02, 1000.0, 0.0)}, {}});
  const SceneForce f = evaluate_scene(scene, {0.1, 0.015, 0}, {}, 1);  // 5 mm deep, above centre
  EXPECT_NEAR(f.F_T_W.y, 5.0, 1e-12);
  EXPECT_NEAR(f.F_T_W.x, 0.0, 1e-12);
  EXPECT_NEAR(f.p_WP.y, 0.02, 1e-15);
  EXPECT_EQ(f.contact_count, 1u);
  // At the exact centre the push is along +z, with the full radius as penetration.
  EXPECT_NEAR(evaluate_scene(scene, {0.1, 0, 0}, {}, 1).F_T_W.z, 20.0, 1e-12);
}

TEST(CompiledScene, SpringFieldIsMinusGradientOfItsPotentialAndClips) {
  SceneDescription d;
  d.fields.push_back({{1, 3, kNeverTick}, FieldSpec{SpringToPointSpec{{0, 0, 0.02}, 20.0, 0.5, 0.0}}});
  const SceneForce f = evaluate_scene(compile(d), {0.01, 0, 0.02}, {0, 0.1, 0}, 1);
  EXPECT_DOUBLE_EQ(f.F_T_W.x, -0.2);
  EXPECT_DOUBLE_EQ(f.F_T_W.y, -0.05);
  EXPECT_EQ(f.contact_count, 0u);
  d.fields[0].spec = FieldSpec{SpringToPointSpec{{0, 0, 0}, 1000.0, 0.0, 2.0}};
  const SceneForce clipped = evaluate_scene(compile(d), {0.03, 0.04, 0}, {}, 1);  // 50 N unclipped
  EXPECT_NEAR(norm(clipped.F_T_W), 2.0, 1e-12);
  EXPECT_NEAR(clipped.F_T_W.x / clipped.F_T_W.y, 0.75, 1e-12);  // direction kept
}

TEST(CompiledScene, FadeGainIsLinearOverTheRamp) {
  EXPECT_EQ(fade_gain(kNeverTick, 5, 50), 1.0);
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
}

}  // namespace
}  // namespace haptic::engine
