// Per-tick cost of each simulated device (read + write: the plant's step at its default sub-steps
// plus everything the device does around it — Jacobians, the motor/brake split, the estimator, the
// disturbance observer) and of each controller on its own, so docs/devices.md's tables come from
// one run. Every device is driven by the same push of the simulated hand; costs are per 1 ms tick.
#include <benchmark/benchmark.h>

#include <dlfcn.h>

#include <chrono>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>

#include "engine/control/brake_rule.hpp"
#include "engine/control/dc_motor_control.hpp"
#include "engine/control/disturbance_observer.hpp"
#include "engine/control/joint_walls.hpp"
#include "engine/control/state_estimator.hpp"
#ifdef HAPLY_DRIVER  // the Haply driver is built (HAPTIC_BUILD_HAPLY_DRIVER)
#include "fake_haply_service.hpp"
#endif
#include "runtime/cartesian_model.hpp"
#include "runtime/dc_motor_model.hpp"
#include "runtime/device_port.hpp"
#include "runtime/driver_device.hpp"
#include "runtime/five_bar_estimator.hpp"
#include "runtime/five_bar_model.hpp"
#include "runtime/joystick_model.hpp"
#include "runtime/parallel_dob_model.hpp"
#include "runtime/simulated_dc_motor_device.hpp"
#include "runtime/simulated_point_mass_device.hpp"
#include "runtime/simulated_dob_device.hpp"
#include "runtime/simulated_five_bar_device.hpp"
#include "runtime/simulated_joystick_device.hpp"

using namespace haptic;

namespace {

constexpr double kT = 1e-3;  // s

engine::HandInput light_push(engine::Vec3 force) {
  engine::HandInput hand;
  hand.mode = engine::HandInput::Mode::kApplyForce;
  hand.force = force;
  return hand;
}

/// One tick of a device with its model: read, estimate, kinematics, then Jᵀ and write a small
/// force (what the loop does around the scene).
void run_device(benchmark::State& state, runtime::Device& device, runtime::DeviceModel& model,
                engine::Vec3 command) {
  runtime::DevicePort port(device, model);
  runtime::ToolReading reading;
  for (auto _ : state) {
    port.read(reading);
    benchmark::DoNotOptimize(reading);
    port.write(runtime::ToolCommand{command}, kT);
  }
}

void BM_Device_PointMass(benchmark::State& state) {
  runtime::SimulatedPointMassDevice device(engine::PointMassParams{}, {{0, 0, 0}, {}}, 20.0);
  runtime::CartesianModel model;
  run_device(state, device, model, {0, 0, 1e-4});
}
BENCHMARK(BM_Device_PointMass);

void BM_Device_DcMotor000(benchmark::State& state) {
  runtime::SimulatedDcMotorDevice device(
      engine::DcMotorParams{},
      state.range(0) ? engine::DcMotorModel::kWithInductance : engine::DcMotorModel::kWithoutInductance,
      0.5, 5.0, engine::IntegrationSettings{});
  runtime::DcMotorModel model(engine::DcMotorParams{}, true);
  run_device(state, device, model, {0, 0, 0});
}
BENCHMARK(BM_Device_DcMotor000)->Arg(0)->Arg(1)->ArgName("with_inductance");

void BM_Device_FiveBar003(benchmark::State& state) {
  runtime::SimulatedFiveBarOptions options;
  options.plant.coriolis = state.range(0) != 0;
  runtime::SimulatedFiveBarDevice device(engine::FiveBarParams{}, {}, options);
  runtime::FiveBarModel model(engine::FiveBarParams{}, options.velocity_cutoff);
  if (state.range(1)) model.set_velocity_estimator(std::make_unique<runtime::FiveBarStateEstimators>(kT));
  device.set_hand(light_push({0.0, 0.0, 0.5}));
  run_device(state, device, model, {0.0, 0.0, -0.5});
}
BENCHMARK(BM_Device_FiveBar003)->ArgsProduct({{1, 0}, {0, 1}})->ArgNames({"coriolis", "estimator"});

void BM_Device_Joystick004(benchmark::State& state) {
  runtime::SimulatedJoystickDevice device(runtime::SimulatedJoystickConfig{});
  runtime::JoystickModel model(runtime::SimulatedJoystickConfig{}.model());
  device.set_hand(light_push({0.2, 0.0, 0.0}));
  run_device(state, device, model, {-0.2, 0.0, 0.0});
}
BENCHMARK(BM_Device_Joystick004);

void BM_Device_ParallelDob001(benchmark::State& state) {
  runtime::SimulatedDobDevice device(engine::Parallel2DofParams{}, {0.0, 0.25, 0.0}, 10.0,
                                     state.range(0) != 0);
  runtime::ParallelDobModel model(engine::Parallel2DofParams{}, engine::DisturbanceObserverParams{},
                                  {0.0, 0.25, 0.0}, state.range(0) != 0);
  run_device(state, device, model, {0.0, 0.0, 0.0});
}
BENCHMARK(BM_Device_ParallelDob001)->Arg(1)->Arg(0)->ArgName("observer");

// The example driver (a point mass behind the driver ABI): called on the loop itself
// (call_timeout 0) against through the driver thread that guards against a hang (the default),
// so the thread hop's cost per tick (two calls, each a futex wake and wait) is measured.
// driver_thread 2: with 1 ms between ticks, as in the loop at 1 kHz, so the driver thread is
// asleep when the tick's read comes (its write then finds it still spinning); 3: the same gaps
// with the calls on the loop (what the pauses themselves cost).
void BM_Device_DriverPointMass(benchmark::State& state) {
  runtime::DriverOptions options;
  options.library = POINT_MASS_DRIVER;
  options.call_timeout_s = state.range(0) == 1 || state.range(0) == 2 ? 0.02 : 0.0;
  runtime::DriverDevice device(options);
  runtime::CartesianModel model;
  device.start();
  if (state.range(0) >= 2) {
    runtime::DevicePort port(device, model);
    runtime::ToolReading reading;
    for (auto _ : state) {
      state.PauseTiming();
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      state.ResumeTiming();
      port.read(reading);
      benchmark::DoNotOptimize(reading);
      port.write(runtime::ToolCommand{{0, 0, 1e-4}}, kT);
    }
  } else {
    run_device(state, device, model, {0, 0, 1e-4});
  }
  device.stop();
}
BENCHMARK(BM_Device_DriverPointMass)->Arg(0)->Arg(1)->ArgName("driver_thread");
BENCHMARK(BM_Device_DriverPointMass)->Arg(2)->Arg(3)->ArgName("driver_thread")->Iterations(1000);

// The Force Dimension driver (driver/vendors) against the stand-in of its runtime
// (tests/driver/standins), calls on the loop (0) or through the driver thread (1); and the same
// runtime calls a tick makes (position, velocity, buttons, force) made straight on the stand-in, so
// the driver's own cost is the difference: the stand-in's share (a mutex, its plant, its call log)
// is not what a real runtime costs, whose USB round trip dominates on hardware.
void BM_Device_DriverForceDimension(benchmark::State& state) {
  setenv("FAKE_DHD_DEVICES", "omega.3", 1);
  runtime::DriverOptions options;
  options.library = FORCEDIMENSION_DRIVER;
  options.params_json = std::string(R"({"library": ")") + FAKE_FORCEDIMENSION_LIBRARY + "\"}";
  options.call_timeout_s = state.range(0) == 1 ? 0.02 : 0.0;
  runtime::DriverDevice device(options);
  runtime::CartesianModel model;
  device.start();
  run_device(state, device, model, {0, 0, 1e-4});
  device.stop();
}
BENCHMARK(BM_Device_DriverForceDimension)->Arg(0)->Arg(1)->ArgName("driver_thread");

void BM_Standin_ForceDimensionCallsAlone(benchmark::State& state) {
  setenv("FAKE_DHD_DEVICES", "omega.3", 1);
  void* runtime = dlopen(FAKE_FORCEDIMENSION_LIBRARY, RTLD_NOW | RTLD_LOCAL);
  if (runtime == nullptr) {
    state.SkipWithError("cannot load the stand-in");
    return;
  }
  using Get3 = int (*)(double*, double*, double*, char);
  using Set3 = int (*)(double, double, double, char);
  const auto open = reinterpret_cast<int (*)(char)>(dlsym(runtime, "dhdOpenID"));
  const auto auto_init = reinterpret_cast<int (*)(char)>(dlsym(runtime, "drdAutoInit"));
  const auto stop_regulation = reinterpret_cast<int (*)(bool, char)>(dlsym(runtime, "drdStop"));
  const auto enable = reinterpret_cast<int (*)(unsigned char, char)>(dlsym(runtime, "dhdEnableForce"));
  const auto position = reinterpret_cast<Get3>(dlsym(runtime, "dhdGetPosition"));
  const auto velocity = reinterpret_cast<Get3>(dlsym(runtime, "dhdGetLinearVelocity"));
  const auto buttons = reinterpret_cast<unsigned (*)(char)>(dlsym(runtime, "dhdGetButtonMask"));
  const auto force = reinterpret_cast<Set3>(dlsym(runtime, "dhdSetForce"));
  const auto close = reinterpret_cast<int (*)(char)>(dlsym(runtime, "dhdClose"));
  const char id = static_cast<char>(open(0));
  auto_init(id);
  stop_regulation(true, id);
  enable(1, id);
  double p[3], v[3];
  for (auto _ : state) {
    position(&p[0], &p[1], &p[2], id);
    velocity(&v[0], &v[1], &v[2], id);
    benchmark::DoNotOptimize(buttons(id));
    benchmark::DoNotOptimize(p);
    force(0.0, 0.0, 1e-4, id);
  }
  close(id);
  dlclose(runtime);
}
BENCHMARK(BM_Standin_ForceDimensionCallsAlone);

// The OpenHaptics driver against the stand-in of the HD runtime, server-clocked: hapticd's read
// and write only exchange the newest sample and force with the runtime's servo callback (running
// on the stand-in's own 1 kHz thread meanwhile), calls on the loop (0) or through the driver
// thread (1).
void BM_Device_DriverOpenHaptics(benchmark::State& state) {
  setenv("FAKE_HD_DEVICES", "rig=Touch", 1);
  unsetenv("FAKE_HD_CLOCK");
  runtime::DriverOptions options;
  options.library = OPENHAPTICS_DRIVER;
  options.params_json = std::string(R"({"device": "rig", "library": ")") + FAKE_OPENHAPTICS_LIBRARY + "\"}";
  options.call_timeout_s = state.range(0) == 1 ? 0.02 : 0.0;
  options.stale_after = 0;  // the benchmark reads far faster than the servo loop samples
  runtime::DriverDevice device(options);
  runtime::CartesianModel model;
  device.start();
  run_device(state, device, model, {0, 0, 1e-4});
  device.stop();
}
BENCHMARK(BM_Device_DriverOpenHaptics)->Arg(0)->Arg(1)->ArgName("driver_thread");

#ifdef HAPLY_DRIVER
// The Haply driver against the stand-in of the Inverse Service (in-process, loopback WebSocket):
// each tick sends the force as JSON and takes the service's answer, so the figure is the round
// trip through the service and back, on the driver thread (the driver's JSON allocates: it is
// not meant to run on the loop).
void BM_Device_DriverHaply(benchmark::State& state) {
  fake_haply::Options service_options;
  service_options.port = 0;
  fake_haply::Service service(service_options);
  std::string error;
  if (!service.start(&error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  runtime::DriverOptions options;
  options.library = HAPLY_DRIVER;
  options.params_json = R"({"url": "ws://127.0.0.1:)" + std::to_string(service.port()) + "\"}";
  options.call_timeout_s = 0.02;
  runtime::DriverDevice device(options);
  runtime::CartesianModel model;
  device.start();
  run_device(state, device, model, {0, 0, 1e-4});
  device.stop();
  service.stop();
}
BENCHMARK(BM_Device_DriverHaply);
#endif

// ---- Controllers on their own: one tick's computation each.

void BM_Controller_TorsionSpring000(benchmark::State& state) {
  const engine::DcMotorParams p;
  engine::VirtualTorsionSpring spring(engine::exact_delayed_coefficients(1.0, 0.01, kT), p.r, 0.0);
  double theta = 0.01;
  for (auto _ : state) {
    benchmark::DoNotOptimize(spring.torque(theta));
    theta = -theta;
  }
}
BENCHMARK(BM_Controller_TorsionSpring000);

void BM_Controller_ConventionalWall003(benchmark::State& state) {
  engine::ConventionalJointWall wall(engine::JointWallParams{800.0, 5.0});
  double q = 1e-3;
  for (auto _ : state) {
    benchmark::DoNotOptimize(wall.torque(q));
    q = -q;
  }
}
BENCHMARK(BM_Controller_ConventionalWall003);

void BM_Controller_EstimatorWall003(benchmark::State& state) {
  engine::JointWallParams params{800.0, 5.0};
  engine::EstimatorJointWall wall(params, engine::StateEstimatorParams{});
  double q = 1e-3;
  for (auto _ : state) {
    benchmark::DoNotOptimize(wall.torque(q, 0.1));
    q = -q;
  }
}
BENCHMARK(BM_Controller_EstimatorWall003);

void BM_Controller_BrakeRule004(benchmark::State& state) {
  const engine::HybridRuleParams rule{7.78, 1e-3};
  double q_dot = 0.3;
  for (auto _ : state) {
    benchmark::DoNotOptimize(engine::split_hybrid(0.5, q_dot, 0.1, rule));
    q_dot = -q_dot;
  }
}
BENCHMARK(BM_Controller_BrakeRule004);

void BM_Controller_DisturbanceObserver001(benchmark::State& state) {
  engine::DisturbanceObserver x_axis{engine::DisturbanceObserverParams{}};
  engine::DisturbanceObserver y_axis{engine::DisturbanceObserverParams{}};
  double v = 0.01;
  for (auto _ : state) {
    const double fx = x_axis.command(1.0, v);
    const double fy = y_axis.command(-1.0, -v);
    x_axis.update(fx, v);
    y_axis.update(fy, -v);
    benchmark::DoNotOptimize(fx + fy);
    v = -v;
  }
}
BENCHMARK(BM_Controller_DisturbanceObserver001);

}  // namespace

BENCHMARK_MAIN();
