#pragma once
// One tick of the loop, in the order of docs/architecture.md:
//   adopt scene -> device.read -> compiled scene -> safety -> device.write -> publish sample.
// Separate from the thread that paces it so tests can run ticks directly (lockstep, allocation
// counting) and both time modes share exactly this code.

#include <atomic>
#include <cstdint>
#include <optional>

#include "engine/safety/force_guard.hpp"
#include "engine/scene/compiled_scene.hpp"
#include "runtime/device.hpp"
#include "runtime/loop_stats.hpp"
#include "runtime/sample_ring.hpp"
#include "runtime/snapshot_exchange.hpp"
#include "engine/safety/passivity.hpp"

namespace haptic::runtime {

using SceneExchange = SnapshotExchange<engine::CompiledScene>;

struct TickConfig {
  double period_s = 0.001;               // Unit: s.
  engine::ForceLimits limits;
  std::int64_t output_ramp_ticks = 50;   // Length of the shutdown ramp, >= 1.
  /// The passivity controller at the device port (Hannaford & Ryu 2002), between the scene and
  /// the force guard; absent: off. It watches the contact force of the scene's objects — where
  /// sampling makes stiff walls active — and adds damping only while the energy observed since
  /// the contact began is negative, so a passive contact passes unchanged. Fields pass through:
  /// a field a client turns on under the tool, or a non-conservative first-order field, is a
  /// deliberate source of energy (metered and reported per field).
  std::optional<engine::PassivityControllerParams> passivity;
};

class TickRunner {
 public:
  TickRunner(Device& device, SceneExchange& scenes, SampleRing& samples, LoopCounters& counters,
             const TickConfig& config);

  /// On the loop: runs tick number `tick` (1, 2, ...) starting at server time `time_ns`.
  void run(std::uint64_t tick, std::int64_t time_ns);

  /// Any thread: from tick `first_tick` on, the output gain falls linearly to zero over
  /// output_ramp_ticks ticks and stays there.
  void begin_output_ramp(std::uint64_t first_tick) {
    ramp_first_tick_.store(first_tick, std::memory_order_release);
  }
  /// True once a tick has run with the output gain at zero.
  bool output_ramp_done() const { return output_zero_.load(std::memory_order_acquire); }

  const TickConfig& config() const { return config_; }

 private:
  double output_gain(std::uint64_t tick) const;

  Device& device_;
  std::optional<engine::PassivityController> passivity_;
  SceneExchange& scenes_;
  SampleRing& samples_;
  LoopCounters& counters_;
  TickConfig config_;
  engine::ForceGuard guard_;
  DeviceReading last_good_reading_;  // what the samples show while the device is faulted
  std::atomic<std::uint64_t> ramp_first_tick_{UINT64_MAX};
  std::atomic<bool> output_zero_{false};
};

}  // namespace haptic::runtime
