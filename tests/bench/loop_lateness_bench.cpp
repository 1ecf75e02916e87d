// Real-time loop lateness against its floor, in one run: at each rate, hapticd's loop (simulated
// device, one wall and one spring field; sleep, then spin the last spin_us) beside a pure
// busy-spin loop (no tick work, never sleeps) on the same CPU at the same priority, so that every
// figure is also a ratio to what this host allows at all. Then the loop with sleep alone, for the
// pacing's sake. Lateness = wake-up − deadline, 1 µs resolution; ratios below are of
// (lateness + 1 µs), since the floor's median is often 0.
// Usage: loop_lateness_bench [seconds=10] [rates=1000,4000,10000] [spin_us]
// (spin_us: the loop's real_time.spin_us; default hapticd's, config::default_spin_us)
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "config/server_config.hpp"
#include "runtime/cartesian_model.hpp"
#include "runtime/loop_cpu.hpp"
#include "runtime/loop_thread.hpp"
#include "runtime/simulated_point_mass_device.hpp"

using namespace haptic;

namespace {

constexpr int kFifoPriority = 80;  // hapticd's default real_time.fifo_priority

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
  std::uint64_t overruns = 0;
  std::uint64_t ticks = 0;
  runtime::RealtimeSetup setup;
};

/// hapticd's loop for `seconds` at `rate_hz`, sleeping until spin_ns before each deadline.
Result run_loop(double seconds, double rate_hz, std::int64_t spin_ns, int cpu) {
  runtime::SimulatedPointMassDevice device(engine::PointMassParams{}, {{0, 0, 0.02}, {}}, 20.0);
  runtime::SceneExchange scenes(std::make_unique<const engine::CompiledScene>(default_scene()));
  runtime::SampleRing samples;
  runtime::LoopCounters counters;
  runtime::LatenessHistogram lateness(static_cast<int>(seconds) + 1);  // the whole run
  runtime::CartesianModel model;
  runtime::TickRunner runner(device, model, scenes, samples, counters,
                             runtime::TickConfig{1.0 / rate_hz, {}, 50, {}});
  runtime::LoopConfig config;
  config.rate_hz = rate_hz;
  config.spin_ns = spin_ns;
  config.fifo_priority = kFifoPriority;
  config.cpu = cpu;
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

/// The floor: a thread at the loop's priority on its CPU that only spins on the clock from one
/// deadline to the next and records how late it saw each.
Result run_busy_spin(double seconds, double rate_hz, int cpu) {
  runtime::LatenessHistogram lateness(static_cast<int>(seconds) + 1);
  Result result;
  std::thread spinner([&] {
    result.setup = runtime::apply_realtime(kFifoPriority);
    if (cpu >= 0) result.setup.cpu_error = runtime::pin_to_cpu(cpu);
    const auto period = static_cast<std::int64_t>(std::llround(1e9 / rate_hz));
    const std::int64_t end = runtime::monotonic_now_ns() + static_cast<std::int64_t>(seconds * 1e9);
    std::int64_t deadline = runtime::monotonic_now_ns() + period;
    while (deadline < end) {
      std::int64_t now = runtime::monotonic_now_ns();
      while (now < deadline) now = runtime::monotonic_now_ns();
      lateness.record(now - deadline, now);
      ++result.ticks;
      deadline += period;
      if (now > deadline) {  // the host took the CPU for longer than a period
        const std::int64_t missed = (now - deadline) / period + 1;
        result.overruns += static_cast<std::uint64_t>(missed);
        deadline += missed * period;
      }
    }
  });
  spinner.join();
  result.lateness = lateness.summarize(runtime::monotonic_now_ns());
  return result;
}

void print(const char* name, const Result& r) {
  std::printf("  %-26s ticks %8llu  lateness p50 %4.0f  p99 %5.0f  p99.9 %5.0f  max %6.0f us  overruns %llu\n",
              name, static_cast<unsigned long long>(r.ticks), r.lateness.p50_us, r.lateness.p99_us,
              r.lateness.p999_us, r.lateness.max_us, static_cast<unsigned long long>(r.overruns));
}

double ratio(double value_us, double floor_us) { return (value_us + 1.0) / (floor_us + 1.0); }

}  // namespace

int main(int argc, char** argv) {
  const double seconds = argc > 1 ? std::atof(argv[1]) : 10.0;
  std::vector<double> rates = {1000.0, 4000.0, 10000.0};
  if (argc > 2) {
    rates.clear();
    std::stringstream in(argv[2]);
    std::string item;
    while (std::getline(in, item, ',')) rates.push_back(std::atof(item.c_str()));
  }
  if (!(seconds >= 1.0 && seconds <= 600.0) ||
      std::any_of(rates.begin(), rates.end(), [](double r) { return !(r >= 100.0 && r <= 10000.0); })) {
    std::fprintf(stderr, "usage: loop_lateness_bench [seconds 1..600] [rates, each 100..10000 Hz]\n");
    return 2;
  }
  // The CPU hapticd's loop would take on this host (claimed for the run).
  const runtime::LoopCpuChoice cpu =
      runtime::choose_loop_cpu(std::nullopt, static_cast<int>(std::thread::hardware_concurrency()));
  std::printf("loop lateness against a busy-spin floor, %.0f s per case, CPU %d, SCHED_FIFO %d\n",
              seconds, cpu.cpu, kFifoPriority);
  for (const double rate : rates) {
    const double period_us = 1e6 / rate;
    // hapticd's default spin at this rate, or the one asked for (less than a period).
    const double spin_us = argc > 3 ? std::atof(argv[3]) : config::default_spin_us(rate);
    const auto spin_ns = static_cast<std::int64_t>(std::min(spin_us, period_us - 1.0) * 1000.0);
    std::printf("%.0f Hz (period %.0f us, spin %lld us)\n", rate, period_us,
                static_cast<long long>(spin_ns / 1000));
    const Result floor = run_busy_spin(seconds, rate, cpu.cpu);
    print("busy-spin floor", floor);
    const Result hybrid = run_loop(seconds, rate, spin_ns, cpu.cpu);
    print("hapticd loop (sleep+spin)", hybrid);
    if (rate == rates.front()) {
      std::printf("  SCHED_FIFO %s, mlockall %s\n", hybrid.setup.fifo ? "on" : "refused",
                  hybrid.setup.memory_locked ? "on" : "refused");
    }
    std::printf("  ratio to the floor: p50 %.2f x, p99 %.2f x (goal <= 1.2 x)\n",
                ratio(hybrid.lateness.p50_us, floor.lateness.p50_us),
                ratio(hybrid.lateness.p99_us, floor.lateness.p99_us));
    if (rate <= 1000.0) {
      const Result sleep_only = run_loop(seconds, rate, 0, cpu.cpu);
      print("loop, sleep only", sleep_only);
    }
  }
  return 0;
}
