// The engine's per-tick work allocates nothing (after Drake's LimitMalloc tests): scene
// evaluation, the force guard and the plant with a simulated hand, over 10,000 ticks.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "engine/device/point_mass_plant.hpp"
#include "engine/operator/simulated_hand.hpp"
#include "engine/safety/force_guard.hpp"
#include "engine/scene/compiled_scene.hpp"
#include "support/allocation_counter.hpp"

namespace haptic::engine {
namespace {

TEST(EngineNoAllocation, TheCounterSeesAnAllocation) {
  haptic::test::reset_allocations();
  {
    haptic::test::CountAllocations counting;
    auto p = std::make_unique<int>(7);
    EXPECT_EQ(*p, 7);
  }
  EXPECT_EQ(haptic::test::allocations(), 1u);
  // Outside a counting scope nothing is counted.
  auto q = std::make_unique<int>(8);
  EXPECT_EQ(haptic::test::allocations(), 1u);
}

SceneDescription busy_scene() {
  SceneDescription d;
  const auto object = [&](Vec3 p, Quat R, double k, double b, auto shape, std::int64_t fade) {
    ObjectSpec spec;
    spec.p_WO = p;
    spec.R_WO = R;
    spec.stiffness = k;
    spec.damping = b;
    spec.shape = shape;
    d.objects.push_back({{1, d.objects.size() + 1, fade, {}}, spec});
  };
  object({0, 0, -0.01}, {}, 1000.0, 1.0, HalfSpaceSpec{{0, 0, 1}}, kNeverTick);
  object({0.02, 0, 0}, {0.9238795, 0, 0.3826834, 0}, 800.0, 0.5, HalfSpaceSpec{{-1, 0, 0}},
         kNeverTick);
  object({0, -0.03, 0}, {}, 500.0, 0.0, HalfSpaceSpec{{0, 1, 0}}, 3000);
  object({0.005, 0.005, 0}, {}, 600.0, 0.2, SphereSpec{0.01}, kNeverTick);
  object({-0.01, 0, 0.01}, {}, 400.0, 0.0, SphereSpec{0.015}, 5000);
  // A lattice of small spheres, enough for the sphere stage's broad phase (kStageSphereGrid).
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) {
      for (int k = 0; k < 6; ++k) {
        object({0.01 * (i - 2.5), 0.01 * (j - 2.5), 0.01 * (k - 2.5)}, {}, 300.0, 0.1, SphereSpec{0.003},
               (i + j + k) % 7 == 0 ? 4000 : kNeverTick);
      }
    }
  }
  d.fields.push_back(
      {{2, 10, kNeverTick, {}}, FieldSpec{SpringToPointSpec{{0, 0, 0}, 50.0, 0.1, 2.0}}});
  d.fields.push_back({{2, 11, 7000, {}}, FieldSpec{SpringToPointSpec{{0.01, 0, 0}, 20.0, 0.0, 0.0}}});
  return d;
}

TEST(EngineNoAllocation, TenThousandTicksOfSceneGuardAndPlantAllocateNothing) {
  const CompiledScene scene = compile_scene(busy_scene(), 50, 1);
  ASSERT_NE(scene.stages & kStageSphereGrid, 0u);
  ForceGuard guard(ForceLimits{});
  PointMassPlant plant(PointMassParams{});
  HandInput hand;
  hand.mode = HandInput::Mode::kFollowTarget;
  hand.stiffness = 200.0;
  hand.damping = 2.0;
  constexpr double kDt = 0.001;
  std::uint32_t contacts = 0;

  haptic::test::reset_allocations();
  {
    haptic::test::CountAllocations counting;
    for (std::int64_t tick = 0; tick < 10000; ++tick) {
      // The hand sweeps its target through the walls and spheres so every branch runs.
      hand.target = {0.03 * std::sin(tick * 0.003), 0.03 * std::cos(tick * 0.005),
                     -0.02 + 0.01 * std::sin(tick * 0.007)};
      const PointMassState& s = plant.state();
      const SceneForce scene_force = evaluate_scene(scene, s.p_WT, s.v_WT, tick);
      contacts += scene_force.contact_count;
      const GuardedForce out = guard.apply(scene_force.F_T_W, kDt);
      plant.step(out.F_T_W, kDt,
                 [&](const Vec3& p, const Vec3& v) { return hand_force(hand, p, v); });
    }
  }
  EXPECT_EQ(haptic::test::allocations(), 0u);
  EXPECT_GT(contacts, 0u);  // the loop did touch something
  EXPECT_TRUE(is_finite(plant.state().p_WT));
}

}  // namespace
}  // namespace haptic::engine
