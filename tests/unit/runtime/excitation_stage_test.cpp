// The identification's excitation stage (runtime/excitation_stage): the multisine along its axis
// from the first tick, a centering spring and damper about the start added where asked, and a
// stop for good when the tool leaves its box or moves too fast.
#include <gtest/gtest.h>

#include "runtime/excitation_stage.hpp"

namespace haptic::runtime {
namespace {

engine::Multisine signal() {
  engine::MultisineParams params;
  params.samples_per_period = 64;
  params.f_min_hz = 20.0;
  params.f_max_hz = 200.0;
  params.ramp_s = 0.0;
  params.periods = 4;
  std::string why;
  const auto m = engine::design_multisine(params, why);
  EXPECT_TRUE(m) << why;
  return *m;
}

ToolReading at(engine::Vec3 p, engine::Vec3 v = {}) {
  ToolReading r;
  r.p_WT = p;
  r.v_WT = v;
  return r;
}

TEST(ExcitationStage, PlaysTheMultisineAlongItsAxisFromTheFirstTick) {
  const engine::Multisine m = signal();
  ExcitationStage stage(m, {0.0, 1.0, 0.0}, {});
  EXPECT_EQ(engine::norm(stage.force(at({0.1, 0.2, 0.3}), 0)), 0.0);  // tick 0: before the run
  for (std::uint64_t tick = 1; tick < 10; ++tick) {
    const engine::Vec3 F = stage.force(at({0.1, 0.2, 0.3}), tick);
    EXPECT_EQ(F.x, 0.0);
    EXPECT_EQ(F.z, 0.0);
    EXPECT_DOUBLE_EQ(F.y, m.force_at_tick(tick - 1));
  }
}

TEST(ExcitationStage, ACenteringSpringAndDamperAboutTheStartAreAddedAlongTheAxis) {
  const engine::Multisine m = signal();
  ExcitationStage stage(m, {1.0, 0.0, 0.0}, {}, {100.0, 2.0});
  stage.force(at({0.5, 0.0, 0.0}), 1);  // the start
  EXPECT_DOUBLE_EQ(stage.start_position().x, 0.5);
  // 3 mm out along the axis, 0.1 m/s outwards; off the axis neither counts.
  const engine::Vec3 F = stage.force(at({0.503, 0.004, 0.0}, {0.1, 0.3, 0.0}), 2);
  EXPECT_NEAR(F.x, m.force_at_tick(1) - 100.0 * 0.003 - 2.0 * 0.1, 1e-12);
  EXPECT_EQ(F.y, 0.0);
}

TEST(ExcitationStage, LeavingTheBoxOrGoingTooFastStopsItForGood) {
  const engine::Multisine m = signal();
  ExcitationStage stage(m, {1.0, 0.0, 0.0}, {0.01, 0.5}, {100.0, 0.0});
  stage.force(at({0.0, 0.0, 0.0}), 1);
  EXPECT_EQ(engine::norm(stage.force(at({0.0, 0.0, 0.02}), 2)), 0.0);
  EXPECT_EQ(stage.stop(), ExcitationStage::Stop::kLeftTheBox);
  EXPECT_EQ(stage.stop_tick(), 2u);
  // Back inside, it stays stopped, the centering too.
  EXPECT_EQ(engine::norm(stage.force(at({0.005, 0.0, 0.0}), 3)), 0.0);

  ExcitationStage fast(m, {1.0, 0.0, 0.0}, {0.01, 0.5});
  fast.force(at({0.0, 0.0, 0.0}), 1);
  EXPECT_EQ(engine::norm(fast.force(at({0.0, 0.0, 0.0}, {0.0, 0.6, 0.0}), 2)), 0.0);
  EXPECT_EQ(fast.stop(), ExcitationStage::Stop::kTooFast);
  EXPECT_DOUBLE_EQ(fast.stop_speed(), 0.6);
}

}  // namespace
}  // namespace haptic::runtime
