// A ROS 2 node's wrench at a device port in lockstep: the server's own TickRunner with a simulated
// point mass held by a scripted hand, and the port's mailbox written as the federation's thread
// writes it (a new wrench every 10 ticks, as a 100 Hz node's would arrive). The force goes through
// the port's own network passivity layer, so a robot pushing the hand can give it back only what
// the hand put in against it; a stale wrench ramps out; a non-finite one never reaches the device.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>

#include "engine/core/rotation.hpp"
#include "haptic/wire/datagram.hpp"
#include "runtime/cartesian_model.hpp"
#include "runtime/five_bar_estimator.hpp"
#include "runtime/five_bar_model.hpp"
#include "runtime/robot_wrench.hpp"
#include "runtime/simulated_five_bar_device.hpp"
#include "runtime/simulated_point_mass_device.hpp"
#include "runtime/tick_runner.hpp"
#include "support/allocation_counter.hpp"

namespace haptic::runtime {
namespace {

constexpr double kPeriod = 1e-3;
constexpr double kMaxForce = 20.0;

engine::PointMassParams point_mass() {
  engine::PointMassParams p;
  p.mass = 0.05;
  p.damping = 0.1;
  p.workspace_min = {-1, -1, -1};
  p.workspace_max = {1, 1, 1};
  return p;
}

/// A hand holding the tool at the origin (200 N/m, 2 N·s/m), or moving it along x by ±amplitude
/// at `hz`.
engine::HandInput hand(double amplitude = 0.0, double hz = 0.0) {
  engine::HandInput h;
  h.mode = engine::HandInput::Mode::kFollowTarget;
  h.stiffness = 200.0;
  h.damping = 2.0;
  if (amplitude > 0.0) {
    h.trajectory.shape = engine::TargetTrajectory::Shape::kSine;
    h.trajectory.amplitude = {amplitude, 0, 0};
    h.trajectory.frequency_hz = hz;
  }
  return h;
}

/// A hand (200 N/m, 2 N·s/m) whose target moves from the origin to `end` over `seconds`, then holds.
engine::HandInput pushing(const engine::Vec3& end, double seconds) {
  engine::HandInput h = hand();
  h.trajectory.shape = engine::TargetTrajectory::Shape::kLine;
  h.trajectory.end = end;
  h.trajectory.duration_s = seconds;
  return h;
}

/// One device port with a robot's wrench, an empty scene (the robot's force is all the device gets).
struct Bench {
  explicit Bench(const engine::HandInput& input, RobotWrenchParams params = {})
      : device(point_mass(), engine::PointMassState{}, kMaxForce),
        scenes(std::make_unique<const engine::CompiledScene>(engine::compile_scene({}, 50, 1, kPeriod))),
        runner({port(params)}, scenes, counters, TickConfig{kPeriod, {}, 50, {}}) {
    device.set_hand(input);
  }

  TickPort port(const RobotWrenchParams& params) {
    TickPort out{&device, &model, &samples, engine::force_limits_for(kMaxForce), std::nullopt};
    out.robot = &robot;
    out.robot_params = params;
    return out;
  }

  /// Stores a wrench as the relay does.
  void send(const engine::Vec3& F_T_W) {
    RobotWrench wrench = robot.load();
    ++wrench.sequence;
    wrench.F_T_W = F_T_W;
    robot.store(wrench);
  }

  /// Runs the next tick; returns its sample, and books the work the force did on the tool.
  TickSample tick() {
    ++ticks;
    runner.run(ticks, static_cast<std::int64_t>(ticks - 1) * 1'000'000);
    TickSample sample;
    samples.read(ticks, sample);
    if (ticks > 1) channel -= engine::dot(previous.F_T_W, sample.p_WT - previous.p_WT);
    lowest = std::min(lowest, channel);
    previous = sample;
    return sample;
  }

  SimulatedPointMassDevice device;
  CartesianModel model;
  SceneExchange scenes;
  SampleRing samples;
  LoopCounters counters;
  LatestValue<RobotWrench> robot;
  TickRunner runner;
  std::uint64_t ticks = 0;
  TickSample previous;
  /// The work the hand did against the robot's force less what the force gave it (J): what the
  /// user put into the channel. Negative: the robot gave the user energy the user never put in.
  double channel = 0.0;
  double lowest = 0.0;
};

// A robot pushes a held tool with a constant 3 N along +x. Rendered as it is, it would take the
// tool to where the hand's 200 N/m balances it (1.5 cm) and give the hand F²/2K = 22.5 mJ it never
// put in. Through the layer the robot can give back only what the hand did against it: held, the
// hand put nothing in and the tool does not move; moved ±2 cm at 0.5 Hz, against the force and with
// it, the hand gets back what it put in, never more; pushed slowly into the force, it feels it.
TEST(RobotWrench, AConstantRobotForceAgainstAHandKeepsTheChannelPassive) {
  Bench held(hand());
  double farthest = 0.0;
  for (int i = 0; i < 2000; ++i) {
    if (i % 10 == 0) held.send({3.0, 0, 0});
    farthest = std::max(farthest, held.tick().p_WT.x);
  }
  std::printf("held 2 s: a 3 N robot force moved the tool %.3g m (1.5e-2 m without the layer), channel energy "
              "down to %.3g J\n", farthest, held.lowest);
  EXPECT_LT(farthest, 1e-4);
  EXPECT_GT(held.lowest, -1e-6);

  Bench moved(hand(0.02, 0.5));
  double injected = 0.0;
  for (int i = 0; i < 10'000; ++i) {
    if (i % 10 == 0) moved.send({3.0, 0, 0});
    const double before = moved.channel;
    moved.tick();
    injected += std::max(0.0, moved.channel - before);
  }
  std::printf("moved ±2 cm at 0.5 Hz for 10 s: the hand put in %.4f J and got back %.4f J; channel energy down "
              "to %.3g J\n", injected, injected - moved.channel, moved.lowest);
  EXPECT_GT(moved.lowest, -1e-6);
  EXPECT_GT(injected, 0.1);  // the hand did push against the force, and felt it
  EXPECT_EQ(moved.counters.force_faults.load(), 0u);

  Bench slow(pushing({-0.02, 0, 0}, 2.0));  // 1 cm/s into the force
  double felt = 0.0;
  for (int i = 0; i < 2000; ++i) {
    if (i % 10 == 0) slow.send({3.0, 0, 0});
    const TickSample s = slow.tick();
    if (i >= 500) felt += s.F_T_W.x / 1500.0;
  }
  std::printf("pushed into it at 1 cm/s: mean force felt %.2f N of 3 N; channel energy down to %.3g J\n", felt,
              slow.lowest);
  EXPECT_GT(felt, 1.5);
  EXPECT_GT(slow.lowest, -1e-6);
}

// The node stops: 0.2 s after its last wrench the force ramps out over the output ramp (50 ms),
// smoother than the guard's rate, and is zero after; when wrenches come again it ramps back in.
// The hand pushes into the force (2 cm/s) so that the layer lets it through.
TEST(RobotWrench, AStaleWrenchRampsOutAndAFreshOneRampsBackIn) {
  Bench bench(pushing({0.03, 0, 0}, 1.5));
  const double guard_step = engine::force_limits_for(kMaxForce).max_force_rate * kPeriod;
  double largest_step = 0.0;
  double last_force = 0.0;
  std::uint64_t last_sent = 0;
  for (int i = 0; i < 600; ++i) {
    if (i < 300 && i % 10 == 0) {
      bench.send({-2.0, 0, 0});
      last_sent = bench.ticks + 1;
    }
    const TickSample s = bench.tick();
    largest_step = std::max(largest_step, std::abs(s.F_T_W.x - last_force));
    last_force = s.F_T_W.x;
    EXPECT_EQ(s.flags & wire::kFlagForceSaturated, 0u) << "tick " << s.tick;
    if (s.tick == last_sent + 150) {
      EXPECT_LT(s.F_T_W.x, -1.0) << "the force went before it was stale";
    }
    if (s.tick >= last_sent + 200 + 50 + 2) {
      EXPECT_LT(std::abs(s.F_T_W.x), 1e-3) << "tick " << s.tick << ": not ramped out";
    }
  }
  std::printf("stale: largest change of the force per tick %.3g N (the guard allows %.3g N)\n", largest_step,
              guard_step);
  EXPECT_LT(largest_step, guard_step);
  for (int i = 0; i < 100; ++i) {
    if (i % 10 == 0) bench.send({-2.0, 0, 0});
    bench.tick();
  }
  EXPECT_LT(bench.previous.F_T_W.x, -1.0) << "a fresh wrench after a stale one did not ramp back in";
}

// A NaN (or infinite) wrench is refused on the loop, counted, and never reaches the device: the
// last good force stays until it is stale, the guard sees no fault.
TEST(RobotWrench, ANonFiniteWrenchNeverReachesTheDevice) {
  Bench bench(pushing({-0.03, 0, 0}, 1.5));
  for (int i = 0; i < 200; ++i) {
    if (i % 10 == 0) bench.send({1.0, 0, 0});
    bench.tick();
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  bench.send({nan, 0, 0});
  double kept = 0.0;
  for (int i = 0; i < 10; ++i) {
    const TickSample s = bench.tick();
    EXPECT_TRUE(std::isfinite(s.F_T_W.x) && std::isfinite(s.F_T_W.y) && std::isfinite(s.F_T_W.z));
    kept += s.F_T_W.x / 10.0;
  }
  EXPECT_GT(kept, 0.2) << "the last good force went";
  bench.send({0, std::numeric_limits<double>::infinity(), 0});
  for (int i = 0; i < 400; ++i) {
    const TickSample s = bench.tick();
    EXPECT_TRUE(std::isfinite(s.F_T_W.x) && std::isfinite(s.F_T_W.y) && std::isfinite(s.F_T_W.z));
    EXPECT_EQ(s.flags & wire::kFlagForceFault, 0u);
  }
  EXPECT_EQ(bench.counters.robot_wrenches_refused.load(), 2u);
  EXPECT_EQ(bench.counters.force_faults.load(), 0u);
  EXPECT_LT(std::abs(bench.previous.F_T_W.x), 1e-3) << "the last good force did not go stale";
  EXPECT_TRUE(std::isfinite(bench.device.plant().state().p_WT.x));
}

// A lockstep reset (fresh ports) does not render again the wrench left in the mailbox; the next
// one that comes is.
TEST(RobotWrench, AfterAResetOnlyANewWrenchIsRendered) {
  Bench bench(pushing({-0.03, 0, 0}, 1.5));
  for (int i = 0; i < 200; ++i) {
    if (i % 10 == 0) bench.send({2.0, 0, 0});
    bench.tick();
  }
  ASSERT_GT(bench.previous.F_T_W.x, 0.5);
  bench.runner.replace_ports({bench.port({})});
  bench.ticks = 0;
  for (int i = 0; i < 100; ++i) EXPECT_EQ(bench.tick().F_T_W.x, 0.0) << "the wrench from before the reset came back";
  for (int i = 0; i < 100; ++i) {
    if (i % 10 == 0) bench.send({2.0, 0, 0});
    bench.tick();
  }
  EXPECT_GT(bench.previous.F_T_W.x, 0.5);
}

// force_scale scales the wrench before the layer: 4 N at 0.5 is felt as 2 N is.
TEST(RobotWrench, ScaledByForceScale) {
  RobotWrenchParams half;
  half.force_scale = 0.5;
  Bench scaled(pushing({0, 0, -0.03}, 1.5), half);
  Bench plain(pushing({0, 0, -0.03}, 1.5));
  for (int i = 0; i < 1000; ++i) {
    if (i % 10 == 0) {
      scaled.send({0, 0, 4.0});
      plain.send({0, 0, 2.0});
    }
    EXPECT_EQ(scaled.tick().F_T_W.z, plain.tick().F_T_W.z);
  }
  EXPECT_GT(plain.previous.F_T_W.z, 1.0);
}

// The same push on document 003's five-bar: angles read through its encoders, velocity
// estimated (a 20 rad/s low-pass), and no apparent mass known (the 0.05 kg fallback). Held, the
// tool does not move. Moved ±2 cm along x at 0.5 Hz, the channel dips at the first stroke's
// reversal (measured -1.0 mJ, of 0.556 J the hand puts in over 10 s): the estimate's lag lets the
// scaling and the layer's damper act on a velocity the tool no longer has. The layer's books are
// of measured positions, so what was given is taken back after (the channel ends at +43 mJ).
TEST(RobotWrench, OnTheFiveBarsEncodersTheChannelStaysPassive) {
  for (const double amplitude : {0.0, 0.02}) {
    SimulatedFiveBarDevice device(engine::FiveBarParams{});
    FiveBarModel model(engine::FiveBarParams{}, 20.0);
    model.set_velocity_estimator(std::make_unique<FiveBarStateEstimators>(kPeriod));
    SceneExchange scenes(std::make_unique<const engine::CompiledScene>(engine::compile_scene({}, 50, 1, kPeriod)));
    SampleRing samples;
    LoopCounters counters;
    LatestValue<RobotWrench> robot;
    TickPort port{&device, &model, &samples, engine::force_limits_for(12.0), std::nullopt};
    port.robot = &robot;
    TickRunner runner({port}, scenes, counters, TickConfig{kPeriod, {}, 50, {}});
    runner.run(1, 0);
    TickSample first;
    samples.read(1, first);
    engine::HandInput h = hand(amplitude, 0.5);
    h.target = first.p_WT;
    device.set_hand(h);
    TickSample previous = first;
    double channel = 0.0, lowest = 0.0, injected = 0.0, moved = 0.0;
    RobotWrench wrench;
    for (std::uint64_t tick = 2; tick <= 10'000; ++tick) {
      if (tick % 10 == 0) {
        ++wrench.sequence;
        wrench.F_T_W = {3.0, 0, 0};
        robot.store(wrench);
      }
      runner.run(tick, static_cast<std::int64_t>(tick - 1) * 1'000'000);
      TickSample s;
      samples.read(tick, s);
      const double W = -engine::dot(previous.F_T_W, s.p_WT - previous.p_WT);
      channel += W;
      injected += std::max(0.0, W);
      lowest = std::min(lowest, channel);
      moved = std::max(moved, engine::norm(s.p_WT - first.p_WT));
      previous = s;
    }
    std::printf("five-bar, %s: the hand put in %.4f J, got back %.4f J; channel energy down to %.3g J, %.4f J at "
                "the end; the tool went %.3g m from where it started\n",
                amplitude > 0.0 ? "moved ±2 cm at 0.5 Hz" : "held", injected, injected - channel, lowest, channel, moved);
    if (amplitude == 0.0) {
      EXPECT_LT(moved, 1e-4);
    }
    EXPECT_GT(lowest, -2e-3) << amplitude;
    EXPECT_GE(channel, 0.0) << amplitude;
    if (amplitude > 0.0) {
      EXPECT_GT(injected, 0.1);
    }
    EXPECT_EQ(counters.force_faults.load(), 0u);
  }
}

// The wrench's torque on the 6-DOF device's handle (1e-4 kg·m², 5e-4 N·m·s/rad; no hand grips
// its rotation), through a layer of its own: 0.05 N·m on a handle at rest never turns it (alone it
// would spin it up towards 100 rad/s); on a handle spinning at 20 rad/s against it, the torque is
// felt, takes its 20 mJ and gives them back (it turns the handle the other way), never more than
// that by the one-period prediction error (measured 8.3 µJ: the spin changes within a period by
// more than a tool's velocity does). On a 3-DOF port it is ignored.
TEST(RobotWrench, ItsTorqueTurnsA6DofHandleOnlyWithEnergyTheHandlePutIn) {
  for (const double w0 : {0.0, -20.0}) {
    SimulatedRotation rotation;
    rotation.params = engine::RotationParams{1e-4, 5e-4, 10};
    rotation.initial.w_WT = {0, 0, w0};
    rotation.max_torque = 0.2;
    SimulatedPointMassDevice device(point_mass(), engine::PointMassState{}, kMaxForce, rotation);
    CartesianModel model;
    SceneExchange scenes(std::make_unique<const engine::CompiledScene>(engine::compile_scene({}, 50, 1, kPeriod)));
    SampleRing samples;
    LoopCounters counters;
    LatestValue<RobotWrench> robot;
    TickPort port{&device, &model, &samples, engine::force_limits_for(kMaxForce), std::nullopt};
    port.robot = &robot;
    TickRunner runner({port}, scenes, counters, TickConfig{kPeriod, {}, 50, {}});
    device.set_hand(hand());
    RobotWrench wrench;
    TickSample previous;
    double channel = 0.0, lowest = 0.0, strongest = 0.0;
    for (std::uint64_t tick = 1; tick <= 3000; ++tick) {
      if (tick % 10 == 1) {
        ++wrench.sequence;
        wrench.tau_T_W = {0, 0, 0.05};
        robot.store(wrench);
      }
      runner.run(tick, static_cast<std::int64_t>(tick - 1) * 1'000'000);
      TickSample s;
      samples.read(tick, s);
      ASSERT_TRUE(s.has_orientation);
      if (tick > 1) {
        // The torque's work over the tick, on the handle's rotation in W.
        const engine::Vec3 turned = engine::rotation_vector(s.R_WT * engine::conjugate(previous.R_WT));
        channel -= engine::dot(previous.tau_T_W, turned);
      }
      lowest = std::min(lowest, channel);
      strongest = std::max(strongest, s.tau_T_W.z);
      previous = s;
    }
    const double angle = engine::rotation_vector(device.rotation()->state().R_WT).z;
    std::printf("handle from %.0f rad/s: torque felt up to %.3f N·m, channel energy down to %.3g J, turned %.3g rad\n",
                w0, strongest, lowest, angle);
    EXPECT_GT(lowest, -2e-5) << w0;
    EXPECT_LE(strongest, 0.05 + 1e-12) << w0;
    if (w0 == 0.0) {
      EXPECT_EQ(strongest, 0.0);
      EXPECT_EQ(angle, 0.0);
    } else {
      EXPECT_GT(strongest, 0.02) << "the torque against the spin was not felt";
    }
    EXPECT_EQ(counters.force_faults.load(), 0u);
  }
  Bench three_dof(hand());
  for (int i = 0; i < 100; ++i) {
    RobotWrench w = three_dof.robot.load();
    ++w.sequence;
    w.tau_T_W = {0.05, 0, 0};
    three_dof.robot.store(w);
    const TickSample s = three_dof.tick();
    EXPECT_FALSE(s.has_orientation);
    EXPECT_EQ(s.tau_T_W, engine::Vec3{});
  }
}

TEST(RobotWrench, ATickWithARobotWrenchAllocatesNothing) {
  Bench bench(hand(0.02, 0.5));
  for (int i = 0; i < 100; ++i) {
    bench.send({3.0, 0, 0});
    bench.tick();
  }
  haptic::test::reset_allocations();
  {
    haptic::test::CountAllocations counting;
    for (std::uint64_t tick = 101; tick <= 1100; ++tick) bench.runner.run(tick, static_cast<std::int64_t>(tick) * 1'000'000);
  }
  EXPECT_EQ(haptic::test::allocations(), 0u);
}

}  // namespace
}  // namespace haptic::runtime
