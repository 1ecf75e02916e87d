#include "runtime/tick_runner.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/core/rotation.hpp"
#include "haptic/wire/datagram.hpp"
#include "runtime/flush_denormals.hpp"

namespace haptic::runtime {

namespace {

/// A force F (or a torque) from a source that books no energy, on a body of `mass` (or inertia)
/// at p moving at v (or its summed rotation and angular velocity), through `layer`, whose
/// reservoir R then holds only what the user did against it.
///
/// A held force pushes the mass through ½ (F/m) T² over the period whatever its velocity, which
/// the layer's T F·v does not predict: against a hand holding still, each such period gives the
/// hand up to F²T²/2m the layer cannot take back, and they add up (with the layer alone a held
/// hand let a 3 N push creep the tool out 1.5 cm and got 23 mJ it never put in; 1 cm and 11 mJ
/// with cancel_along_velocity). So F is first scaled (s in [0, 1]) to what R pays for over the
/// coming period, its own push included:
///   s T F·v + s² T² |F|² / 2m ≤ R,
/// with m the device's apparent mass (the hand's adds to it: the real push is smaller, so this
/// errs towards less force). The layer then books what was done and damps any remainder. Nothing
/// is received from the source and all R holds is kept (an unbounded keep): nothing is sent.
engine::Vec3 from_passive_source(engine::NetworkPassivity& layer, const engine::Vec3& F_requested,
                                 const engine::Vec3& v, const engine::Vec3& p, double mass, double T) {
  engine::Vec3 F = F_requested;
  const double F2 = engine::dot(F, F);
  if (F2 > 0.0) {
    const double a = T * T * F2 / (2.0 * mass);
    const double b = T * engine::dot(F, v);
    const double discriminant = b * b + 4.0 * a * layer.reservoir();
    const double s = discriminant < 0.0 ? 0.0 : std::clamp((-b + std::sqrt(discriminant)) / (2.0 * a), 0.0, 1.0);
    F = s * F;
  }
  return layer.apply(F, v, p, std::numeric_limits<double>::infinity()).F_T_W;
}

/// A network passivity layer at a device port: its damper capped at what stops the device's mass
/// (or, for a torque, its inertia) within one period T; the default cap where that is unknown (0).
engine::NetworkPassivityParams port_layer(double mass, double T) {
  engine::NetworkPassivityParams params;
  params.period = T;
  params.max_deficit_J = engine::kCouplingMaxDeficitJ;
  if (mass > 0.0) params.max_damping = mass / T;
  return params;
}

}  // namespace

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
    out.remote = port.remote;
    out.ledger = port.ledger;
    out.avatar = port.avatar;
    out.robot = port.robot;
    out.robot_params = port.robot_params;
    if (port.robot) {
      out.robot_layer.emplace(port_layer(description.apparent_mass, config_.period_s));
      // What is in the mailbox already (before a lockstep reset) is not rendered again: stale
      // until a new wrench comes.
      out.robot_sequence = port.robot->load().sequence;
      out.robot_age_ticks = std::numeric_limits<std::int64_t>::max();
    }
    if (description.capabilities.orientation && description.capabilities.torque &&
        description.max_torque > 0.0) {
      out.torque_guard.emplace(engine::force_limits_for(description.max_torque));
      // The robot's torque on the handle, where the device takes torques and knows its inertia.
      if (port.robot && description.apparent_inertia > 0.0) {
        out.robot_torque_layer.emplace(port_layer(description.apparent_inertia, config_.period_s));
      }
    }
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
    if (port.remote) F_scene += avatar_force(port, reading);
    // A ROS 2 node's wrench (a robot's), through a layer of its own, before the guard too.
    if (port.robot) F_scene += robot_force(port, reading);
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
    sample.flags |= wire::kFlagDeviceFault;
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
  }

  if (device.write_device(config_.period_s) != DeviceStatus::kOk) {
    counters_.device_errors.fetch_add(1, std::memory_order_relaxed);
    device.enter_safe_state();
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
  const engine::Vec3 tau_robot = port.robot_torque_layer ? robot_torque(port, reading) : engine::Vec3{};
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

engine::Vec3 TickRunner::avatar_force(Port& port, const ToolReading& reading) {
  const RemoteToolSet remote = port.remote->load();
  engine::Vec3 total;
  for (std::size_t slot = 0; slot < kMaxRemoteTools; ++slot) {
    RemoteTool tool = remote.tools[slot];
    if (tool.key == 0 && port.coupling_keys[slot] != 0 && port.fade_left[slot] == 0) {
      // Its site went quiet: the avatar fades out over the output ramp, as a removed item does,
      // held where the tool was last heard and still limited by the coupling's layer.
      port.fade_left[slot] = config_.output_ramp_ticks;
    }
    if (port.fade_left[slot] > 0 && tool.key == 0) {
      tool = port.last_heard[slot];
      tool.v_WT = {};
    } else if (tool.key != port.coupling_keys[slot] || (tool.key != 0 && port.fade_left[slot] > 0)) {
      // Another remote tool in this slot (or the same one back while fading): a new coupling,
      // with nothing booked.
      port.fade_left[slot] = 0;
      port.coupling_keys[slot] = tool.key;
      port.couplings[slot].reset();
      if (tool.key != 0) {
        port.couplings[slot].emplace(port_layer(port.device.description().apparent_mass, config_.period_s));
      }
    }
    if (!port.couplings[slot]) {
      // No coupling in the slot: its books are cleared once, not written every tick.
      if (port.ledger && port.ledger->key(slot) != 0) port.ledger->record(slot, CouplingBooks{});
      continue;
    }
    double gain = 1.0;
    if (port.fade_left[slot] > 0) {
      gain = static_cast<double>(port.fade_left[slot]) / static_cast<double>(config_.output_ramp_ticks);
      if (--port.fade_left[slot] == 0) {  // faded: the coupling ends
        port.coupling_keys[slot] = 0;
        port.couplings[slot].reset();
        if (port.ledger) port.ledger->record(slot, CouplingBooks{});
        continue;
      }
    } else {
      port.last_heard[slot] = tool;
    }
    engine::NetworkPassivity& coupling = *port.couplings[slot];
    coupling.receive(tool.energy_sent_to_us);
    const engine::Vec3 apart = reading.p_WT - tool.p_WT;
    const double distance = engine::norm(apart);
    const double depth = port.avatar.radius - distance;
    engine::Vec3 F;
    double stored = 0.0;
    if (depth > 0.0 && distance > 0.0) {
      const engine::Vec3 n = (1.0 / distance) * apart;
      const double push = port.avatar.stiffness * depth - port.avatar.damping * engine::dot(reading.v_WT - tool.v_WT, n);
      F = gain * std::max(0.0, push) * n;
      stored = gain * 0.5 * port.avatar.stiffness * depth * depth;
    }
    total += coupling.apply(F, reading.v_WT, reading.p_WT, stored).F_T_W;
    if (port.ledger) {
      port.ledger->record(slot, CouplingBooks{port.coupling_keys[slot], coupling.sent(), coupling.received(),
                                              coupling.injected(), coupling.given(), coupling.reservoir()});
    }
  }
  return total;
}

engine::Vec3 TickRunner::robot_force(Port& port, const ToolReading& reading) {
  const RobotWrench wrench = port.robot->load();
  if (wrench.sequence != port.robot_sequence) {
    port.robot_sequence = wrench.sequence;
    const engine::Vec3 F = port.robot_params.force_scale * wrench.F_T_W;
    const engine::Vec3 tau = port.robot_params.force_scale * wrench.tau_T_W;
    if (std::isfinite(F.x) && std::isfinite(F.y) && std::isfinite(F.z) && std::isfinite(tau.x) &&
        std::isfinite(tau.y) && std::isfinite(tau.z)) {
      port.robot_F_T_W = F;
      port.robot_tau_T_W = tau;
      port.robot_age_ticks = 0;
    } else {
      // Refused: the last good force stays and ages as if nothing had come.
      counters_.robot_wrenches_refused.fetch_add(1, std::memory_order_relaxed);
    }
  }
  if (port.robot_sequence == 0) return {};  // nothing has come yet: no work to book
  // Fresh: the gain ramps (back) in; stale: out, over the loop's output ramp either way.
  const bool stale = static_cast<double>(port.robot_age_ticks) * config_.period_s > port.robot_params.stale_s;
  const double step = 1.0 / static_cast<double>(config_.output_ramp_ticks);
  port.robot_gain = stale ? std::max(0.0, port.robot_gain - step) : std::min(1.0, port.robot_gain + step);
  if (!stale) ++port.robot_age_ticks;
  // The robot's side books no energy: the reservoir holds exactly the work this port's user did
  // against the force less what the force gave back. The layer runs on after a ramp-out: a
  // deficit left by the last period is paid back, and the reservoir stays for the next wrench.
  // A device that does not know its mass is taken as the one the layer's default damper cap
  // stops in a period (0.05 kg at 1 kHz).
  const double apparent = port.device.description().apparent_mass;
  const double mass = apparent > 0.0 ? apparent : engine::NetworkPassivityParams{}.max_damping * config_.period_s;
  return from_passive_source(*port.robot_layer, port.robot_gain * port.robot_F_T_W, reading.v_WT, reading.p_WT,
                             mass, config_.period_s);
}

engine::Vec3 TickRunner::robot_torque(Port& port, const ToolReading& reading) {
  // The handle's rotation since the last tick, in W (R_k = ΔR R_k−1), summed: the "position" whose
  // change the layer books the torque's work on.
  if (port.robot_R_known) {
    port.robot_theta_W += engine::rotation_vector(reading.R_WT * engine::conjugate(port.robot_R_previous));
  }
  port.robot_R_previous = reading.R_WT;
  port.robot_R_known = true;
  if (port.robot_sequence == 0) return {};
  return from_passive_source(*port.robot_torque_layer, port.robot_gain * port.robot_tau_T_W, reading.w_WT,
                             port.robot_theta_W, port.device.description().apparent_inertia, config_.period_s);
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
