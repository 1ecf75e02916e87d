// One tick of the loop against the simulated device, in lockstep: wall contact, removal ramps,
// shutdown ramp, the NaN guard, reproducibility, and no allocation inside a tick.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "haptic/wire/datagram.hpp"
#include "runtime/cartesian_model.hpp"
#include "runtime/loop_thread.hpp"
#include "runtime/simulated_point_mass_device.hpp"
#include "runtime/tick_runner.hpp"
#include "support/allocation_counter.hpp"

namespace haptic::runtime {
namespace {

constexpr double kPeriod = 0.001;

engine::CompiledScene wall_scene(double stiffness, double damping,
                                 std::int64_t fade_begin = engine::kNeverTick,
                                 std::uint64_t generation = 1) {
  engine::SceneDescription description;
  engine::ObjectSpec wall;
  wall.stiffness = stiffness;
  wall.damping = damping;
  wall.shape = engine::HalfSpaceSpec{{0.0, 0.0, 1.0}};
  description.objects.push_back(engine::ObjectEntry{{1, 1, fade_begin, {}}, wall});
  return engine::compile_scene(description, 50, generation);
}

/// A device, a scene exchange, a ring and a runner wired as the server wires them.
struct Rig {
  explicit Rig(engine::CompiledScene scene = {}, double z0 = 0.01)
      : device(engine::PointMassParams{}, engine::PointMassState{{0.0, 0.0, z0}, {}}, 20.0),
        scenes(std::make_unique<const engine::CompiledScene>(std::move(scene))),
        runner(device, model, scenes, samples, counters, TickConfig{kPeriod, {}, 50, {}}) {}

  TickSample run(std::uint64_t ticks) {
    TickSample last;
    for (std::uint64_t i = 0; i < ticks; ++i) {
      ++tick;
      runner.run(tick, static_cast<std::int64_t>(tick - 1) * 1'000'000);
    }
    samples.read(tick, last);
    return last;
  }

  SimulatedPointMassDevice device;
  CartesianModel model;
  SceneExchange scenes;
  SampleRing samples;
  LoopCounters counters;
  TickRunner runner;
  std::uint64_t tick = 0;
};

engine::HandInput push(double fz) {
  engine::HandInput hand;
  hand.mode = engine::HandInput::Mode::kApplyForce;
  hand.force = {0.0, 0.0, fz};
  return hand;
}

TEST(TickRunner, PushIntoWallSettlesWhereWallForceBalancesThePush) {
  // A 5 N push (Eom et al.'s operator force) into a K = 1000 N/m wall: rest at 5 mm penetration.
  Rig rig(wall_scene(1000.0, 1.0));
  rig.device.set_hand(push(-5.0));
  const TickSample s = rig.run(3000);
  EXPECT_NEAR(s.p_WT.z, -0.005, 1e-6);
  EXPECT_NEAR(s.F_T_W.z, 5.0, 1e-3);
  EXPECT_EQ(s.contact_count, 1u);
  // The force at each sample is exactly K × penetration − B v_n for that sample's state.
  EXPECT_NEAR(s.F_T_W.z, -1000.0 * s.p_WT.z - 1.0 * s.v_WT.z, 1e-9);
  EXPECT_DOUBLE_EQ(s.p_WP.z, 0.0);  // proxy on the surface
}

TEST(TickRunner, RemovedWallFadesOutLinearlyOverTheRamp) {
  Rig rig(wall_scene(1000.0, 1.0));
  rig.device.set_hand(push(-5.0));
  ASSERT_NEAR(rig.run(3000).F_T_W.z, 5.0, 1e-3);
  // The fade begins at the next tick (3001) and lasts 50 ticks.
  rig.scenes.publish(std::make_unique<const engine::CompiledScene>(wall_scene(1000.0, 1.0, 3001, 2)));
  for (std::uint64_t k = 0; k <= 60; ++k) {
    const TickSample s = rig.run(1);
    const double gain = std::max(0.0, 1.0 - static_cast<double>(k) / 50.0);
    const double unfaded = std::max(0.0, -1000.0 * s.p_WT.z - 1.0 * s.v_WT.z);
    ASSERT_NEAR(s.F_T_W.z, gain * unfaded, 1e-9) << "tick " << s.tick;
    // Flagged while the force is ramping, and no longer once it has reached zero.
    ASSERT_EQ((s.flags & wire::kFlagRampingOut) != 0, k < 50) << "tick " << s.tick;
  }
}

TEST(TickRunner, ShutdownRampTakesTheForceToZeroAndKeepsItThere) {
  Rig rig(wall_scene(1000.0, 1.0));
  rig.device.set_hand(push(-5.0));
  rig.run(3000);
  rig.runner.begin_output_ramp(3001);
  EXPECT_FALSE(rig.runner.output_ramp_done());
  const TickSample mid = rig.run(25);
  EXPECT_GT(mid.F_T_W.z, 0.0);
  const TickSample end = rig.run(30);
  EXPECT_EQ(end.F_T_W.z, 0.0);
  EXPECT_TRUE(rig.runner.output_ramp_done());
}

TEST(TickRunner, NonFiniteSceneForceNeverReachesTheDevice) {
  // An infinite-stiffness wall cannot come from the validated control plane; the guard must still
  // stop the NaN/inf it produces.
  Rig rig(wall_scene(std::numeric_limits<double>::infinity(), 0.0), -0.001);
  const TickSample s = rig.run(1);
  EXPECT_EQ(s.F_T_W.z, 0.0);
  EXPECT_TRUE(s.flags & wire::kFlagForceFault);
  EXPECT_EQ(rig.counters.force_faults.load(), 1u);
  EXPECT_TRUE(std::isfinite(rig.device.description().max_force));
}

/// A device whose plant "blows up" from a given tick on: its reading becomes NaN.
/// A runner around `device` against a 1000 N/m wall through z = 0, wired as the server wires it.
struct WallRig {
  explicit WallRig(Device& device)
      : scenes(std::make_unique<const engine::CompiledScene>(wall_scene(1000.0, 0.0))),
        runner(device, model, scenes, samples, counters, TickConfig{kPeriod, {}, 50, {}}) {}
  CartesianModel model;
  SceneExchange scenes;
  SampleRing samples;
  LoopCounters counters;
  TickRunner runner;
};

class FailingDevice final : public Device {
 public:
  explicit FailingDevice(std::uint64_t fail_from) : fail_from_(fail_from) {
    description_.name = "failing";
  }
  const DeviceDescription& description() const override { return description_; }
  DeviceStatus start() override { return DeviceStatus::kOk; }
  void stop() override {}
  DeviceStatus read(DeviceReading& reading) override {
    ++reads_;
    reading.q = {0.0, 0.0, -0.001};
    if (reads_ >= fail_from_) reading.q[2] = std::numeric_limits<double>::quiet_NaN();
    return DeviceStatus::kOk;  // the device does not notice: the runner must
  }
  DeviceStatus write(const DeviceCommand& command, double) override {
    last_command = {command.tau[0], command.tau[1], command.tau[2]};
    ++writes;
    return DeviceStatus::kOk;
  }
  void enter_safe_state() override { ++safe_state_entries; }
  engine::Vec3 last_command;
  int writes = 0;
  int safe_state_entries = 0;

 private:
  DeviceDescription description_;
  std::uint64_t fail_from_;
  std::uint64_t reads_ = 0;
};

TEST(TickRunner, NonFiniteReadingFaultsToZeroForceAndShowsTheLastGoodState) {
  FailingDevice device(3);
  WallRig rig(device);
  rig.runner.run(1, 0);
  rig.runner.run(2, 1'000'000);
  EXPECT_NEAR(device.last_command.z, 1.0, 1e-12);  // 1 mm into a 1000 N/m wall
  EXPECT_EQ(device.safe_state_entries, 0);
  rig.runner.run(3, 2'000'000);
  rig.runner.run(4, 3'000'000);
  EXPECT_EQ(device.last_command, engine::Vec3{});  // at once, not ramped
  EXPECT_EQ(device.writes, 4);
  EXPECT_EQ(device.safe_state_entries, 2);  // motors off, brakes on, on every faulted tick
  EXPECT_EQ(rig.counters.device_errors.load(), 2u);
  TickSample s;
  ASSERT_TRUE(rig.samples.read(4, s));
  EXPECT_TRUE(s.flags & wire::kFlagDeviceFault);
  EXPECT_EQ(s.p_WT.z, -0.001);  // the last good reading, never NaN
  EXPECT_EQ(s.F_T_W, engine::Vec3{});
}

/// A device that reads well and whose writes fail from a given write on (a cable pulled between
/// the reading and the command).
class WriteFailingDevice final : public Device {
 public:
  explicit WriteFailingDevice(int fail_from) : fail_from_(fail_from) {}
  const DeviceDescription& description() const override { return description_; }
  DeviceStatus start() override { return DeviceStatus::kOk; }
  void stop() override {}
  DeviceStatus read(DeviceReading& reading) override {
    reading.q = {0.0, 0.0, -0.001};
    return DeviceStatus::kOk;
  }
  DeviceStatus write(const DeviceCommand&, double) override {
    return ++writes_ >= fail_from_ ? DeviceStatus::kError : DeviceStatus::kOk;
  }
  void enter_safe_state() override { ++safe_state_entries; }
  int safe_state_entries = 0;

 private:
  DeviceDescription description_;
  int fail_from_;
  int writes_ = 0;
};

TEST(TickRunner, ACommandThatCouldNotBeWrittenIsAFaultAndNoForceIsShownAsApplied) {
  WriteFailingDevice device(2);
  WallRig rig(device);
  rig.runner.run(1, 0);
  TickSample s;
  ASSERT_TRUE(rig.samples.read(1, s));
  EXPECT_FALSE(s.flags & wire::kFlagDeviceFault);
  EXPECT_NEAR(s.F_T_W.z, 1.0, 1e-12);  // 1 mm into a 1000 N/m wall, written
  rig.runner.run(2, 1'000'000);
  ASSERT_TRUE(rig.samples.read(2, s));
  EXPECT_TRUE(s.flags & wire::kFlagDeviceFault) << "the write failed";
  EXPECT_EQ(s.F_T_W, engine::Vec3{}) << "the wall's force never reached the device";
  EXPECT_EQ(s.p_WT.z, -0.001);  // the reading was good: it is shown
  EXPECT_EQ(rig.counters.device_errors.load(), 1u);
  EXPECT_EQ(device.safe_state_entries, 1);
}

/// A device that holds its safe state (a tripped watchdog) from a given tick on, reading well.
class LatchedDevice final : public Device {
 public:
  explicit LatchedDevice(std::uint64_t latch_from) : latch_from_(latch_from) {}
  const DeviceDescription& description() const override { return description_; }
  DeviceStatus start() override { return DeviceStatus::kOk; }
  void stop() override {}
  DeviceStatus read(DeviceReading& reading) override {
    ++reads_;
    reading.q = {0.0, 0.0, -0.001 * static_cast<double>(reads_)};
    reading.safe_state = reads_ >= latch_from_;
    return DeviceStatus::kOk;
  }
  DeviceStatus write(const DeviceCommand& command, double) override {
    last_command = {command.tau[0], command.tau[1], command.tau[2]};
    return DeviceStatus::kOk;
  }
  engine::Vec3 last_command;

 private:
  DeviceDescription description_;
  std::uint64_t latch_from_;
  std::uint64_t reads_ = 0;
};

TEST(TickRunner, ADeviceInItsSafeStateIsAFaultThatStillShowsWhereItIs) {
  LatchedDevice device(2);
  WallRig rig(device);
  rig.runner.run(1, 0);
  EXPECT_GT(device.last_command.z, 0.0);
  rig.runner.run(2, 1'000'000);
  EXPECT_EQ(device.last_command, engine::Vec3{});
  EXPECT_EQ(rig.counters.device_errors.load(), 1u);
  TickSample s;
  ASSERT_TRUE(rig.samples.read(2, s));
  EXPECT_TRUE(s.flags & wire::kFlagDeviceFault);
  EXPECT_EQ(s.p_WT.z, -0.002);  // this tick's reading, not the last one before the fault
}

TEST(TickRunner, SameInputsGiveBitIdenticalSamples) {
  auto run_once = [] {
    Rig rig(wall_scene(1000.0, 1.0));
    engine::HandInput hand;
    hand.mode = engine::HandInput::Mode::kFollowTarget;
    hand.target = {0.001, -0.002, -0.01};
    hand.stiffness = 200.0;
    hand.damping = 2.0;
    rig.device.set_hand(hand);
    std::vector<TickSample> out;
    for (int i = 0; i < 500; ++i) out.push_back(rig.run(1));
    return out;
  };
  const auto a = run_once();
  const auto b = run_once();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].p_WT, b[i].p_WT);
    ASSERT_EQ(a[i].F_T_W, b[i].F_T_W);
  }
}

TEST(TickRunner, NoAllocationInsideTenThousandTicksWithSceneSwapsBetween) {
  Rig rig(wall_scene(1000.0, 1.0));
  rig.device.set_hand(push(-5.0));
  // The counter must see an allocation when one happens, or a zero below proves nothing.
  {
    test::reset_allocations();
    test::CountAllocations counting;
    auto probe = std::make_unique<int>(7);
    ASSERT_EQ(test::allocations(), 1u);
  }
  std::uint64_t inside = 0;
  for (int block = 0; block < 100; ++block) {
    // Off the loop: a new scene every 100 ticks (a wall that moves and a sphere and a spring).
    engine::SceneDescription description;
    engine::ObjectSpec wall;
    wall.p_WO = {0.0, 0.0, -0.0001 * block};
    wall.stiffness = 1000.0;
    wall.damping = 1.0;
    wall.shape = engine::HalfSpaceSpec{{0.0, 0.0, 1.0}};
    description.objects.push_back({{1, 1, engine::kNeverTick, {}}, wall});
    engine::ObjectSpec sphere = wall;
    sphere.p_WO = {0.05, 0.0, 0.0};
    sphere.shape = engine::SphereSpec{0.01};
    description.objects.push_back({{1, 2, block % 2 ? 1 : engine::kNeverTick, {}}, sphere});
    description.fields.push_back(
        {{2, 3, engine::kNeverTick, {}}, engine::FieldSpec{engine::SpringToPointSpec{{}, 10.0, 0.1, 2.0}}});
    rig.scenes.publish(std::make_unique<const engine::CompiledScene>(
        engine::compile_scene(description, 50, static_cast<std::uint64_t>(block) + 2)));
    test::reset_allocations();
    {
      test::CountAllocations counting;
      rig.run(100);
    }
    inside += test::allocations();
    rig.scenes.reclaim();
  }
  EXPECT_EQ(rig.tick, 10000u);
  EXPECT_EQ(inside, 0u);
}

TEST(TickRunner, TwoPortsPushOneVirtualMassTogetherWithoutAllocating_Eq7_1) {
  // Two point masses side by side, each with its own ring, and a 100 g box (B_V = 4 N·s/m) in
  // front of both; each hand pushes +x.
  SimulatedPointMassDevice device0(engine::PointMassParams{}, {{0.0, 0.0, 0.0}, {}}, 20.0);
  SimulatedPointMassDevice device1(engine::PointMassParams{}, {{0.0, 0.02, 0.0}, {}}, 20.0);
  engine::SceneDescription description;
  engine::ObjectSpec box;
  box.p_WO = {0.02, 0.01, 0.0};
  box.stiffness = 1000.0;
  box.damping = 2.0;
  box.shape = engine::BoxSpec{{0.005, 0.03, 0.01}};
  box.object_mass = 0.1;
  box.object_damping = 4.0;
  description.objects.push_back({{1, 1, engine::kNeverTick, {}}, box});
  SceneExchange scenes(std::make_unique<const engine::CompiledScene>(
      engine::compile_scene(description, 50, 1, kPeriod, 0.0, 2)));
  SampleRing ring0, ring1;
  LoopCounters counters;
  CartesianModel model0, model1;
  TickRunner runner({TickPort{&device0, &model0, &ring0, {}, {}}, TickPort{&device1, &model1, &ring1, {}, {}}}, scenes,
                    counters, TickConfig{kPeriod, {}, 50, {}});
  engine::HandInput hand0 = push(0.0), hand1 = push(0.0);
  hand0.force = {0.2, 0.0, 0.0};
  hand1.force = {0.3, 0.0, 0.0};
  device0.set_hand(hand0);
  device1.set_hand(hand1);
  std::uint64_t tick = 0;
  auto run = [&](int ticks) {
    for (int i = 0; i < ticks; ++i) {
      ++tick;
      runner.run(tick, static_cast<std::int64_t>(tick - 1) * 1'000'000);
    }
  };
  run(100);
  test::reset_allocations();
  {
    test::CountAllocations counting;
    run(600);
  }
  EXPECT_EQ(test::allocations(), 0u);
  TickSample s0, s1;
  ASSERT_TRUE(ring0.read(tick, s0));
  ASSERT_TRUE(ring1.read(tick, s1));
  // Both tools and the box move at (F_0 + F_1) / (B_V + b_0 + b_1); each ring holds its own tool.
  const double b = engine::PointMassParams{}.damping;
  const double v = 0.5 / (4.0 + 2.0 * b);
  EXPECT_NEAR(s0.v_WT.x, v, 1e-4);
  EXPECT_NEAR(s1.v_WT.x, v, 1e-4);
  EXPECT_NEAR(s0.p_WT.y, 0.0, 1e-12);
  EXPECT_NEAR(s1.p_WT.y, 0.02, 1e-12);
  EXPECT_NEAR(-s0.F_T_W.x, 0.2 - b * v, 2e-3);
  EXPECT_NEAR(-s1.F_T_W.x, 0.3 - b * v, 2e-3);
  EXPECT_EQ(counters.ticks.load(), tick);  // one count per tick, not per port
}

/// An empty scene and the default device behind a lockstep loop.
struct LockstepRig {
  LockstepRig() { loop.start(); }
  SimulatedPointMassDevice device{engine::PointMassParams{}, {}, 20.0};
  CartesianModel model;
  SceneExchange scenes{std::make_unique<const engine::CompiledScene>()};
  SampleRing samples;
  LoopCounters counters;
  LatenessHistogram lateness;
  TickRunner runner{device, model, scenes, samples, counters, TickConfig{}};
  LoopThread loop{runner, counters, lateness, LoopConfig{1000.0, TimeMode::kLockstep}};
};

TEST(LoopThread, LockstepStepRunsExactlyTheTicksAskedFor) {
  LockstepRig rig;
  LoopThread& loop = rig.loop;
  SampleRing& samples = rig.samples;
  TickRunner& runner = rig.runner;
  LoopCounters& counters = rig.counters;
  EXPECT_EQ(loop.step(10).tick, 10u);
  EXPECT_EQ(loop.step(5).tick, 15u);
  EXPECT_EQ(loop.server_time_ns(), 15 * 1'000'000);
  TickSample s;
  ASSERT_TRUE(samples.read(15, s));
  EXPECT_EQ(s.time_ns, 14 * 1'000'000);  // tick k starts at (k - 1) periods
  loop.ramp_out_and_stop();
  EXPECT_TRUE(runner.output_ramp_done());
  EXPECT_EQ(counters.ticks.load(), loop.completed_ticks());
}

TEST(LoopThread, StepAfterStopReturnsAtOnce) {
  LockstepRig rig;
  LoopThread& loop = rig.loop;
  EXPECT_EQ(loop.step(3).tick, 3u);
  loop.stop();
  EXPECT_EQ(loop.step(1000).tick, 3u);  // nothing runs any more, and the caller is not stranded
}

// A reset right after a step, however the loop thread is placed when it comes, numbers the ticks
// from 1 again and starts a new run; the next step runs exactly its own ticks (no hang, no ticks
// nobody asked for). Many rounds, to meet the loop thread at every point of its cycle.
TEST(LoopThread, AResetRightAfterAStepRestartsTheTicksWithoutLosingOrAddingAny) {
  LockstepRig rig;
  LoopThread& loop = rig.loop;
  for (std::uint64_t round = 1; round <= 300; ++round) {
    ASSERT_EQ(loop.step(static_cast<std::uint32_t>(1 + round % 3)).tick, 1 + round % 3) << "round " << round;
    bool idle_saw_old_ticks = false;
    ASSERT_TRUE(loop.reset_lockstep([&](const std::function<void()>& restart) {
      idle_saw_old_ticks = loop.completed_ticks() == 1 + round % 3;
      restart();
      return loop.completed_ticks() == 0;
    })) << "round " << round;
    EXPECT_TRUE(idle_saw_old_ticks);
    EXPECT_EQ(loop.run(), round);
  }
  const LoopThread::Stepped stepped = loop.step(7);
  EXPECT_EQ(stepped.tick, 7u);
  EXPECT_EQ(stepped.run, 300u);
  EXPECT_EQ(loop.server_time_ns(), 7 * 1'000'000);
}

}  // namespace
}  // namespace haptic::runtime
