#include "runtime/tick_runner.hpp"

#include <algorithm>

#include "haptic/wire/datagram.hpp"
#include "runtime/flush_denormals.hpp"

namespace haptic::runtime {

TickRunner::TickRunner(Device& device, DeviceModel& model, SceneExchange& scenes,
                       SampleRing& samples, LoopCounters& counters, const TickConfig& config)
    : TickRunner(std::vector<TickPort>{TickPort{&device, &model, &samples, config.limits, config.passivity}},
                 scenes, counters, config) {}

TickRunner::TickRunner(const std::vector<TickPort>& ports, SceneExchange& scenes,
                       LoopCounters& counters, const TickConfig& config)
    : scenes_(scenes), counters_(counters), config_(config) {
  config_.output_ramp_ticks = std::max<std::int64_t>(1, config_.output_ramp_ticks);
  make_ports(ports);
}

void TickRunner::make_ports(const std::vector<TickPort>& ports) {
  ports_.clear();
  ports_.reserve(ports.size());
  for (const TickPort& port : ports) {
    const DeviceDescription& description = port.device->description();
    Port& out = ports_.emplace_back(Port{DevicePort(*port.device, *port.model), port.samples,
                                         std::nullopt, engine::ForceGuard(port.limits), ToolReading{},
                                         description.capabilities.orientation, std::nullopt});
    if (port.passivity) out.passivity.emplace(*port.passivity);
    if (description.capabilities.orientation && description.capabilities.torque &&
        description.max_torque > 0.0) {
      out.torque_guard.emplace(engine::force_limits_for(description.max_torque));
    }
    if (port.remote) {
      out.remote_tools.emplace(*port.remote, port.ledger, port.avatar, description.apparent_mass, config_.period_s,
                               config_.output_ramp_ticks);
    }
    if (port.robot) {
      out.robot.emplace(*port.robot, port.robot_params, description, out.torque_guard.has_value(), config_.period_s,
                        config_.output_ramp_ticks, counters_.robot_wrenches_refused);
    }
    out.excitation = port.excitation;
  }
}

void TickRunner::replace_ports(const std::vector<TickPort>& ports) {
  make_ports(ports);
  // A shutdown ramp asked for meanwhile still applies: from the new run's first tick.
  if (ramp_first_tick_.load(std::memory_order_acquire) != UINT64_MAX) {
    ramp_first_tick_.store(1, std::memory_order_release);
  }
  output_zero_.store(false, std::memory_order_release);
}

double TickRunner::output_gain(std::uint64_t tick) const {
  const std::uint64_t first = ramp_first_tick_.load(std::memory_order_acquire);
  if (tick < first) return 1.0;
  const double elapsed = static_cast<double>(tick - first);
  return std::max(0.0, 1.0 - elapsed / static_cast<double>(config_.output_ramp_ticks));
}

void TickRunner::run(std::uint64_t tick, std::int64_t time_ns) {
  const FlushDenormals no_denormals;  // a state decaying to rest must not slow the loop down
  // A new scene takes over the contacts, filters and meters of the items it shares with the last.
  const engine::CompiledScene& scene = scenes_.adopt(
      [](const engine::CompiledScene& from, const engine::CompiledScene& to) {
        engine::carry_state(from, to);
      });
  const double gain = output_gain(tick);
  const auto ports = static_cast<std::uint32_t>(ports_.size());
  for (std::uint32_t index = 0; index < ports; ++index) run_port(scene, index, tick, time_ns, gain);
  // Federation: the masses shared across sites are pulled towards the other sites' copies.
  if (config_.shared_masses != nullptr) config_.shared_masses->run(scene, tick);
  // The virtual masses move once, under the reactions of every port (000 eq. 7.1).
  if (!scene.masses.empty() || !scene.mesh_masses.empty()) engine::advance_scene(scene, config_.period_s);
  if (gain == 0.0) output_zero_.store(true, std::memory_order_release);
  counters_.ticks.fetch_add(1, std::memory_order_relaxed);
}

void TickRunner::run_port(const engine::CompiledScene& scene, std::uint32_t index,
                          std::uint64_t tick, std::int64_t time_ns, double gain) {
  Port& port = ports_[index];
  DevicePort& device = port.device;
  TickSample sample;
  sample.tick = tick;
  sample.time_ns = time_ns;

  // device.read -> estimate -> kinematics: the tool point's state.
  const bool read_good = device.sense();
  ToolReading reading = device.tool();
  const bool read_ok = read_good && !reading.safe_state;
  engine::Vec3 F_command;
  bool command_ok = false;
  if (read_ok) {
    port.last_good_reading = reading;
    const engine::SceneForce scene_force = engine::evaluate_scene_port(
        scene, index, reading.p_WT, reading.v_WT, static_cast<std::int64_t>(tick), config_.period_s);
    sample.p_WP = scene_force.p_WP;
    sample.contact_count = scene_force.contact_count;
    if (scene_force.ramping || gain < 1.0) sample.flags |= wire::kFlagRampingOut;
    engine::Vec3 F_scene = scene_force.F_T_W;
    if (port.passivity) {
      // The port is watched every tick, in contact or not, so the held force's work is booked
      // for every period. Out of contact the account keeps a deficit — a stiff wall's bounce
      // lasts two or three samples and ends owing energy — but drops a surplus, so a long passive
      // contact cannot bank energy that hides a later active one.
      const engine::Vec3 F_contacts = scene_force.F_T_W - scene_force.F_fields_W;
      const engine::PassivityStep step = port.passivity->apply(F_contacts, reading.v_WT, reading.p_WT);
      if (step.alpha > 0.0) counters_.passivity_active_ticks.fetch_add(1, std::memory_order_relaxed);
      F_scene = step.F_T_W + scene_force.F_fields_W;
      if (F_contacts == engine::Vec3{} && port.passivity->energy() > 0.0) port.passivity->reset();
    }
    // Other sites' tools (federation): each through its own network passivity layer, after the
    // port's controller (which watches this site's contacts) and before the guard.
    if (port.remote_tools) F_scene += port.remote_tools->force(reading);
    // A ROS 2 node's wrench (a robot's), through a layer of its own, before the guard too.
    if (port.robot) F_scene += port.robot->force(reading);
    // An identification's excitation, before the guard as well: it reaches the device as a
    // command does.
    if (port.excitation != nullptr) F_scene += port.excitation->force(reading, tick);
    F_command = guarded(port.guard.apply(F_scene, config_.period_s, gain), sample);
    const engine::Vec3 tau_command = port_torque(scene, index, reading, tick, gain, sample);
    // Jᵀ: the joint command for that force (the torque goes to the handle as it is).
    command_ok = device.joint_command(ToolCommand{F_command, tau_command}, config_.period_s) ==
                 DeviceStatus::kOk;
    if (command_ok) sample.tau_T_W = tau_command;
    if (!command_ok) counters_.device_errors.fetch_add(1, std::memory_order_relaxed);
  } else {
    // A failed or non-finite reading is a device fault: command zero at once (no ramp: nothing
    // justifies any force), and publish the last good state, never a NaN.
    counters_.device_errors.fetch_add(1, std::memory_order_relaxed);
    if (read_good) {
      port.last_good_reading = reading;  // a device holding its safe state still reports where it is
    } else {
      reading = port.last_good_reading;
    }
    sample.p_WP = reading.p_WT;
    port.guard.reset();
    if (port.torque_guard) port.torque_guard->reset();
  }
  if (!command_ok) {
    F_command = {};
    device.enter_safe_state();
    sample.flags |= wire::kFlagDeviceFault;  // a reading that failed, or a command the model refused
  }

  if (device.write_device(config_.period_s) != DeviceStatus::kOk) {
    counters_.device_errors.fetch_add(1, std::memory_order_relaxed);
    device.enter_safe_state();
    // The command did not reach the device: the sample says so, and shows no force as applied
    // (the safe state holds zero), so that no client takes a force for delivered that was not.
    sample.flags |= wire::kFlagDeviceFault;  // not written
    F_command = {};
    sample.tau_T_W = {};
  }

  sample.p_WT = reading.p_WT;
  sample.v_WT = reading.v_WT;
  sample.R_WT = reading.R_WT;
  sample.w_WT = reading.w_WT;
  sample.has_orientation = port.oriented;
  sample.buttons = reading.buttons;
  sample.F_T_W = F_command;
  port.samples->publish(sample);
}

engine::Vec3 TickRunner::port_torque(const engine::CompiledScene& scene, std::uint32_t index,
                                     const ToolReading& reading, std::uint64_t tick, double gain,
                                     TickSample& sample) {
  Port& port = ports_[index];
  if (!port.torque_guard) return {};
  const bool fields = (scene.stages & engine::kStageOrientation) != 0;
  // A ROS 2 node's torque (with its force), through its own layer.
  const engine::Vec3 tau_robot = port.robot && port.robot->has_torque() ? port.robot->torque(reading) : engine::Vec3{};
  // Without orientation fields nothing is computed, but a torque left from a scene that had them
  // still falls at the guard's rate, never as a step.
  if (!fields && tau_robot == engine::Vec3{} && port.torque_guard->last() == engine::Vec3{}) return {};
  engine::Vec3 tau_scene = tau_robot;
  if (fields) {
    const engine::SceneTorque torque = engine::evaluate_scene_orientation(
        scene, index, reading.R_WT, reading.w_WT, static_cast<std::int64_t>(tick), config_.period_s);
    if (torque.ramping) sample.flags |= wire::kFlagRampingOut;
    tau_scene += torque.tau_T_W;
  }
  return guarded(port.torque_guard->apply(tau_scene, config_.period_s, gain), sample);
}

engine::Vec3 TickRunner::guarded(const engine::GuardedForce& out, TickSample& sample) {
  if (out.fault) {
    sample.flags |= wire::kFlagForceFault;
    counters_.force_faults.fetch_add(1, std::memory_order_relaxed);
  }
  if (out.saturated) {
    sample.flags |= wire::kFlagForceSaturated;
    counters_.force_saturations.fetch_add(1, std::memory_order_relaxed);
  }
  return out.F_T_W;
}

}  // namespace haptic::runtime
