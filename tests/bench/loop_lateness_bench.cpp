// Real-time loop lateness: runs the loop (simulated device, one wall and one spring field) in real
// time and prints lateness percentiles and overruns, once with the hybrid sleep-then-spin pacing and
// once with sleep alone, in the same run so the ratio is meaningful on a noisy machine.
// Usage: loop_lateness_bench [seconds=10] [rate_hz=1000]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <thread>

#include "runtime/loop_thread.hpp"
#include "runtime/cartesian_model.hpp"
#include "runtime/simulated_point_mass_device.hpp"

using namespace haptic;

namespace {

engine::CompiledScene default_scene() {
  engine::SceneDescription description;
  engine::ObjectSpec wall;
  wall.stiffness = 1000.0;
  wall.damping = 1.0;
  wall.shape = engine::HalfSpaceSpec{{0.0, 0.0, 1.0}};
  description.objects.push_back({{1, 1, engine::kNeverTick, {}}, wall});
  description.fields.push_back(
      {{1, 2, engine::kNeverTick, {}}, engine::FieldSpec{engine::SpringToPointSpec{{0, 0, 0.02}, 20.0, 0.0, 0.0}}});
  return engine::compile_scene(description, 50, 1);
}

struct Result {
  runtime::LatenessSummary lateness;
  std::uint64_t overruns;
  std::uint64_t ticks;
  runtime::RealtimeSetup setup;
};

Result run(double seconds, double rate_hz, std::int64_t spin_ns) {
  runtime::SimulatedPointMassDevice device(engine::PointMassParams{}, {{0, 0, 0.02}, {}}, 20.0);
  runtime::SceneExchange scenes(std::make_unique<const engine::CompiledScene>(default_scene()));
  runtime::SampleRing samples;
  runtime::LoopCounters counters;
  // A window as long as the run: the whole run is summarized.
  runtime::LatenessHistogram lateness(static_cast<int>(seconds) + 1);
  runtime::CartesianModel model;
  runtime::TickRunner runner(device, model, scenes, samples, counters,
                             runtime::TickConfig{1.0 / rate_hz, {}, 50, {}});
  runtime::LoopConfig config;
  config.rate_hz = rate_hz;
  config.spin_ns = spin_ns;
  runtime::LoopThread loop(runner, counters, lateness, config);
  Result result;
  result.setup = loop.start();
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  loop.stop();
  result.lateness = lateness.summarize(runtime::monotonic_now_ns());
  result.overruns = counters.overruns.load();
  result.ticks = counters.ticks.load();
  return result;
}

void print(const char* name, const Result& r) {
  std::printf("%-22s ticks %7llu  lateness p50 %5.0f us  p99 %5.0f us  p99.9 %5.0f us  max %6.0f us"
              "  overruns %llu\n",
              name, static_cast<unsigned long long>(r.ticks), r.lateness.p50_us, r.lateness.p99_us,
              r.lateness.p999_us, r.lateness.max_us, static_cast<unsigned long long>(r.overruns));
}

}  // namespace

int main(int argc, char** argv) {
  const double seconds = argc > 1 ? std::atof(argv[1]) : 10.0;
  const double rate = argc > 2 ? std::atof(argv[2]) : 1000.0;
  std::printf("loop lateness, %.0f Hz, %.0f s per mode\n", rate, seconds);
  const Result hybrid = run(seconds, rate, 100'000);
  std::printf("SCHED_FIFO %s, mlockall %s\n", hybrid.setup.fifo ? "on" : "refused",
              hybrid.setup.memory_locked ? "on" : "refused");
  print("sleep + 100 us spin", hybrid);
  const Result sleep_only = run(seconds, rate, 0);
  print("sleep only", sleep_only);
  if (hybrid.lateness.p99_us > 0) {
    std::printf("p99 ratio sleep-only / hybrid: %.2f\n", sleep_only.lateness.p99_us / hybrid.lateness.p99_us);
  }
  std::printf("target: hybrid p99 <= 100 us with FIFO permitted -> %s\n",
              hybrid.lateness.p99_us <= 100.0 ? "met" : "NOT met");
  return 0;
}
