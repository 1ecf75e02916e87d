// Per-tick compute cost (Google Benchmark): the whole TickRunner tick on the default scene (one
// wall, one spring field) with the simulated device, the scene evaluation alone, and scenes of
// growing size, so the ratios to the empty scene come from one run.
#include <benchmark/benchmark.h>

#include <memory>

#include "engine/core/rotation.hpp"
#include "engine/device/dc_motor_plant.hpp"
#include "runtime/cartesian_model.hpp"
#include "runtime/simulated_point_mass_device.hpp"
#include "runtime/tick_runner.hpp"

using namespace haptic;

namespace {

engine::CompiledScene scene_with(int walls, int spheres, int springs, int orientation_springs = 0) {
  engine::SceneDescription description;
  std::uint64_t id = 1;
  for (int i = 0; i < walls; ++i) {
    engine::ObjectSpec wall;
    wall.p_WO = {0.0, 0.0, -0.001 * i};
    wall.stiffness = 1000.0;
    wall.damping = 1.0;
    wall.shape = engine::HalfSpaceSpec{{0.0, 0.0, 1.0}};
    description.objects.push_back({{1, id++, engine::kNeverTick, {}}, wall});
  }
  for (int i = 0; i < spheres; ++i) {
    engine::ObjectSpec sphere;
    sphere.p_WO = {0.001 * i, 0.0, 0.0};
    sphere.stiffness = 1000.0;
    sphere.shape = engine::SphereSpec{0.01};
    description.objects.push_back({{1, id++, engine::kNeverTick, {}}, sphere});
  }
  for (int i = 0; i < springs; ++i) {
    description.fields.push_back({{1, id++, engine::kNeverTick, {}},
                                  engine::FieldSpec{engine::SpringToPointSpec{{0, 0, 0.02}, 20.0, 0.1, 0.0}}});
  }
  for (int i = 0; i < orientation_springs; ++i) {
    engine::OrientationSpringSpec spring;
    spring.stiffness = 0.05;
    spring.damping = 2e-4;
    spring.law = engine::ContactLaw::kExactZoh;
    description.fields.push_back({{1, id++, engine::kNeverTick, {}}, engine::FieldSpec{spring}});
  }
  return engine::compile_scene(description, 50, 1);
}

/// Runs whole ticks of `scene` on `device` (a 5 N hand pushing down) for the benchmark's loop.
void run_ticks(benchmark::State& state, runtime::SimulatedPointMassDevice& device, engine::CompiledScene scene) {
  runtime::SceneExchange scenes(std::make_unique<const engine::CompiledScene>(std::move(scene)));
  runtime::SampleRing samples;
  runtime::LoopCounters counters;
  runtime::CartesianModel model;
  runtime::TickRunner runner(device, model, scenes, samples, counters, runtime::TickConfig{});
  engine::HandInput hand;
  hand.mode = engine::HandInput::Mode::kApplyForce;
  hand.force = {0.0, 0.0, -5.0};
  device.set_hand(hand);
  std::uint64_t tick = 0;
  for (auto _ : state) {
    ++tick;
    runner.run(tick, static_cast<std::int64_t>(tick) * 1'000'000);
  }
}

void BM_TickDefaultScene(benchmark::State& state) {
  runtime::SimulatedPointMassDevice device(engine::PointMassParams{}, {{0, 0, -0.001}, {}}, 20.0);
  run_ticks(state, device, scene_with(1, 0, 1));
}
BENCHMARK(BM_TickDefaultScene);

/// The default scene's whole tick on the 6-DOF point mass (its handle stepped with 10 sub-steps),
/// without and with an orientation spring (Arg 1: exact-ZOH law): against BM_TickDefaultScene,
/// what the turning handle costs, and what the orientation stage adds where a scene has it.
void BM_TickSixDof(benchmark::State& state) {
  runtime::SimulatedRotation rotation;
  rotation.initial.R_WT = engine::quat_from_axis_angle({0, 0, 1}, 0.2);
  runtime::SimulatedPointMassDevice device(engine::PointMassParams{}, {{0, 0, -0.001}, {}}, 20.0, rotation);
  run_ticks(state, device, scene_with(1, 0, 1, static_cast<int>(state.range(0))));
}
BENCHMARK(BM_TickSixDof)->Arg(0)->Arg(1)->ArgName("orientation_spring");

void BM_EvaluateScene(benchmark::State& state) {
  const auto n = static_cast<int>(state.range(0));
  const engine::CompiledScene scene = scene_with(n, n, n);
  engine::Vec3 p{0.0, 0.0, -0.0005};
  const engine::Vec3 v{0.0, 0.0, -0.01};
  std::int64_t tick = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(engine::evaluate_scene(scene, p, v, ++tick));
    benchmark::ClobberMemory();
  }
  state.counters["items"] = 3 * n;
}
BENCHMARK(BM_EvaluateScene)->Arg(0)->Arg(1)->Arg(3)->Arg(333);

// Plant step cost per simulated millisecond (one 1 kHz tick) at each plant's default sub-steps:
// document 000's motor with and without inductance (the full model sub-steps to resolve t_e).
void BM_DcMotorStep(benchmark::State& state) {
  const auto model = state.range(0) == 0 ? engine::DcMotorModel::kWithoutInductance
                                         : engine::DcMotorModel::kWithInductance;
  engine::DcMotorPlant plant(engine::DcMotorParams{}, model);
  double u = 0.5;
  for (auto _ : state) {
    plant.step(u, 0.001);
    u = -u;  // a square wave keeps the state moving
    benchmark::DoNotOptimize(plant.state());
  }
  state.counters["substeps"] = plant.substeps_for(0.001);
}
BENCHMARK(BM_DcMotorStep)->Arg(0)->Arg(1)->ArgName("with_inductance");

void BM_PointMassStep(benchmark::State& state) {
  engine::PointMassPlant plant(engine::PointMassParams{});
  engine::Vec3 F{0.0, 0.0, 0.5};
  for (auto _ : state) {
    plant.step(F, 0.001, [](const engine::Vec3&, const engine::Vec3&) { return engine::Vec3{}; });
    F = -F;
    benchmark::DoNotOptimize(plant.state());
  }
}
BENCHMARK(BM_PointMassStep);

}  // namespace

BENCHMARK_MAIN();
