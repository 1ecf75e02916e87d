#pragma once
// One tick of the loop, in the order of docs/architecture.md:
//   adopt scene -> per device port: device.read -> estimate -> kinematics -> compiled scene at
//   that port -> passivity -> avatars -> ROS 2 wrench -> force guard -> torque -> Jᵀ ->
//   device.write -> publish that port's sample -> shared masses -> advance the virtual masses.
// The federation's steps are stages of their own (RemoteToolStage, RobotWrenchStage,
// SharedMassStage), present only where configured.
// Separate from the thread that paces it so tests can run ticks directly (lockstep, allocation
// counting) and both time modes share exactly this code.

#include <array>
#include <atomic>
#include <cstdint>
#include <optional>
#include <vector>

#include "engine/safety/force_guard.hpp"
#include "engine/scene/compiled_scene.hpp"
#include "runtime/device.hpp"
#include "runtime/device_model.hpp"
#include "runtime/device_port.hpp"
#include "runtime/loop_stats.hpp"
#include "runtime/sample_ring.hpp"
#include "runtime/snapshot_exchange.hpp"
#include "engine/safety/passivity.hpp"
#include "runtime/latest_value.hpp"
#include "runtime/remote_tool_stage.hpp"
#include "runtime/remote_tools.hpp"
#include "runtime/robot_wrench.hpp"
#include "runtime/excitation_stage.hpp"
#include "runtime/robot_wrench_stage.hpp"
#include "runtime/shared_masses.hpp"

namespace haptic::runtime {

using SceneExchange = SnapshotExchange<engine::CompiledScene>;

struct TickConfig {
  double period_s = 0.001;               // Unit: s.
  /// Port 0's force limits (and passivity, below) for the one-device constructor; the ports
  /// constructor takes each port's own from its TickPort.
  engine::ForceLimits limits;
  std::int64_t output_ramp_ticks = 50;   // Length of the shutdown ramp, >= 1.
  /// The passivity controller at the device port (Hannaford & Ryu 2002), between the scene and
  /// the force guard; absent: off. It watches the contact force of the scene's objects — where
  /// sampling makes stiff walls active — and adds damping only while the energy observed since
  /// the contact began is negative, so a passive contact passes unchanged. Fields pass through:
  /// a field a client turns on under the tool, or a non-conservative first-order field, is a
  /// deliberate source of energy (metered and reported per field).
  std::optional<engine::PassivityControllerParams> passivity;
  /// Federation: couples the scene's masses shared across sites to the other sites' copies
  /// before they advance; null: none. Not owned.
  SharedMassStage* shared_masses = nullptr;
};

/// One device port: a device (one user's tool) and its model, evaluated against the shared scene,
/// with its own force limits, passivity controller and the ring its samples are published to.
struct TickPort {
  Device* device = nullptr;
  DeviceModel* model = nullptr;
  SampleRing* samples = nullptr;
  engine::ForceLimits limits;
  std::optional<engine::PassivityControllerParams> passivity;  // absent: off
  /// Other sites' tools (federation), rendered as avatars through each coupling's network
  /// passivity layer; null: none, and no avatar work at all. Not owned.
  const LatestValue<RemoteToolSet>* remote = nullptr;
  CouplingLedger* ledger = nullptr;  // with remote: what each coupling sent. Not owned.
  AvatarParams avatar{};
  /// A ROS 2 node's wrench for this tool (federation.ros2.wrench_input): its force, scaled, through
  /// a network passivity layer of its own whose reservoir holds only what this port's user did
  /// against it (first scaled down to what that pays for over the coming period, its push on the
  /// device's apparent mass included), after the avatars and before the guard; ramped out when
  /// stale; a non-finite one is refused (counted in robot_wrenches_refused). Its torque, taken as
  /// the torque on the handle about the tool point in W, goes the same way to a port that takes
  /// torques and knows its apparent inertia; elsewhere (3-DOF ports) it is ignored. Null: none.
  /// Not owned.
  const LatestValue<RobotWrench>* robot = nullptr;
  RobotWrenchParams robot_params{};
  /// An identification's excitation (haptic-lab identify): its force added before the guard, as
  /// the robot's is. Null: none, and no excitation work. Not owned: its owner reads, after the
  /// run, whether and why it stopped.
  ExcitationStage* excitation = nullptr;
};

class TickRunner {
 public:
  /// One device: port 0 with config.limits and config.passivity.
  TickRunner(Device& device, DeviceModel& model, SceneExchange& scenes, SampleRing& samples, LoopCounters& counters,
             const TickConfig& config);
  /// Several device ports sharing one scene (compiled with at least ports.size() ports), run in
  /// order each tick; config.limits and config.passivity are not used. ports is not empty.
  TickRunner(const std::vector<TickPort>& ports, SceneExchange& scenes, LoopCounters& counters,
             const TickConfig& config);

  /// On the loop: runs tick number `tick` (1, 2, ...) starting at server time `time_ns`: every
  /// port in order (each publishes its sample to its own ring, the last port's last), then the
  /// virtual masses advance once under all the ports' reactions.
  void run(std::uint64_t tick, std::int64_t time_ns);

  /// Off the loop, while it runs no tick (a lockstep reset): the ports become `ports` (fresh
  /// devices), each with a fresh passivity controller, force guard and last good reading; an
  /// output ramp already asked for starts again from tick 1 (ticks are numbered afresh). Same
  /// number of ports as before.
  void replace_ports(const std::vector<TickPort>& ports);

  /// Any thread: from tick `first_tick` on, the output gain falls linearly to zero over
  /// output_ramp_ticks ticks and stays there.
  void begin_output_ramp(std::uint64_t first_tick) {
    ramp_first_tick_.store(first_tick, std::memory_order_release);
  }
  /// True once a tick has run with the output gain at zero.
  bool output_ramp_done() const { return output_zero_.load(std::memory_order_acquire); }

  const TickConfig& config() const { return config_; }

 private:
  /// What the loop keeps per port (sized at construction).
  struct Port {
    DevicePort device;
    SampleRing* samples;
    std::optional<engine::PassivityController> passivity;
    engine::ForceGuard guard;
    ToolReading last_good_reading;  // what the samples show while the device is faulted
    bool oriented;                  // the device measures the tool's orientation
    /// The torque's guard (NaN to zero, the device's max_torque, its rate): only for a device
    /// that measures orientation and takes torques up to a known max_torque; without one no orientation work is done.
    std::optional<engine::ForceGuard> torque_guard;
    /// Federation's stages, where configured: other sites' tools, a ROS 2 node's wrench.
    std::optional<RemoteToolStage> remote_tools{};
    std::optional<RobotWrenchStage> robot{};
    ExcitationStage* excitation = nullptr;  // not owned (TickPort::excitation)
  };

  double output_gain(std::uint64_t tick) const;
  void make_ports(const std::vector<TickPort>& ports);
  void run_port(const engine::CompiledScene& scene, std::uint32_t index, std::uint64_t tick,
                std::int64_t time_ns, double gain);
  /// What a guard let through (force or torque), its fault and saturation flagged in the sample
  /// and counted.
  engine::Vec3 guarded(const engine::GuardedForce& out, TickSample& sample);
  /// The orientation fields' torque at this port, guarded; zero without them.
  engine::Vec3 port_torque(const engine::CompiledScene& scene, std::uint32_t index,
                           const ToolReading& reading, std::uint64_t tick, double gain,
                           TickSample& sample);

  std::vector<Port> ports_;
  SceneExchange& scenes_;
  LoopCounters& counters_;
  TickConfig config_;
  std::atomic<std::uint64_t> ramp_first_tick_{UINT64_MAX};
  std::atomic<bool> output_zero_{false};
};

}  // namespace haptic::runtime
