#include "lab/lab_run.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <sstream>
#include <vector>

#include "config/server_config.hpp"
#include "config/devices.hpp"
#include "haptic/wire/datagram.hpp"
#include "schema/scene_specs.hpp"
#include "runtime/loop_stats.hpp"
#include "runtime/realtime.hpp"
#include "runtime/tick_runner.hpp"

namespace haptic::lab {
namespace {

/// The configuration's own scene, as the server's session 0 would hold it (always there: no
/// ramp-in, so a run starts with the scene in place).
engine::SceneDescription initial_scene(const v1::ServerConfig& config, const schema::SceneLimits& limits) {
  schema::SceneSpecs specs;
  if (auto e = schema::to_scene_specs(config.initial_scene(), "initial_scene.", limits, specs); !e.empty()) {
    throw std::invalid_argument(e);
  }
  engine::SceneDescription description;
  std::uint64_t id = 1;
  for (engine::ObjectSpec& spec : specs.objects) {
    engine::ObjectEntry entry;
    entry.meta.id = id++;
    entry.spec = std::move(spec);
    description.objects.push_back(std::move(entry));
  }
  for (engine::FieldSpec& spec : specs.fields) {
    engine::FieldEntry entry;
    entry.meta.id = id++;
    entry.spec = std::move(spec);
    description.fields.push_back(std::move(entry));
  }
  return description;
}

/// The joint state of a simulated device's plant (JointState's table); count 0 for a device
/// without one (a driver's: its plant is not ours to see).
JointState plant_joints(const runtime::SimulatedDevice* device) {
  runtime::JointVector q{}, q_dot{};
  JointState out;
  if (device == nullptr) return out;
  out.count = std::min<std::uint32_t>(device->plant_joints(q, q_dot), 3);
  for (std::uint32_t i = 0; i < out.count; ++i) {
    out.q[i] = q[i];
    out.q_dot[i] = q_dot[i];
  }
  return out;
}

}  // namespace

RunSummary simulate_scene(const v1::ServerConfig& given, double duration_s, const TickCallback& on_tick,
                          const PortsHook& adjust_ports, const DeviceTime& device_time) {
  if (!(std::isfinite(duration_s) && duration_s > 0.0 && duration_s <= 3600.0)) {
    throw std::invalid_argument("duration: must be in (0, 3600] s, got " + std::to_string(duration_s));
  }
  if (!on_tick) throw std::invalid_argument("on_tick: must be a callable");
  v1::ServerConfig config = given;
  config::fill_defaults(config);
  if (auto e = config::validate(config); !e.empty()) throw std::invalid_argument(e);
  const double period_s = 1.0 / config.loop_rate_hz();
  // A run is whole ticks: a duration between two is a mistake, not something to round away.
  const double exact_ticks = duration_s * config.loop_rate_hz();
  if (std::abs(exact_ticks - std::round(exact_ticks)) > 1e-6 * std::max(1.0, exact_ticks) ||
      std::round(exact_ticks) < 1.0) {
    const double below = std::max(1.0, std::floor(exact_ticks)) * period_s;
    const double above = std::max(1.0, std::ceil(exact_ticks)) * period_s;
    std::ostringstream message;
    message << "duration: " << duration_s << " s is " << exact_ticks << " ticks at " << config.loop_rate_hz()
            << " Hz; give a whole number of ticks (" << below << " or " << above << " s)";
    throw std::invalid_argument(message.str());
  }

  std::vector<config::PortDevice> devices = config::make_devices(config);
  const auto ports = static_cast<std::uint32_t>(devices.size());
  std::vector<std::unique_ptr<runtime::SampleRing>> rings;
  std::vector<runtime::SampleRing*> ring_pointers;
  for (std::uint32_t i = 0; i < ports; ++i) {
    rings.push_back(std::make_unique<runtime::SampleRing>());
    ring_pointers.push_back(rings.back().get());
  }
  schema::SceneLimits limits;
  limits.period_s = period_s;
  const config::DesignDevice design = config::scene_design_device(devices);  // as hapticd validates
  limits.device_mass = design.mass;
  limits.device_damping = design.damping;
  limits.device_unknown_reason = design.unknown_reason;
  const engine::SceneDescription description = initial_scene(config, limits);
  engine::HandInput hand;
  if (auto e = schema::to_hand_input(config.initial_operator(), "initial_operator", limits, hand); !e.empty()) {
    throw std::invalid_argument(e);
  }
  for (auto& device : devices) {
    if (device.simulated != nullptr) device.simulated->set_hand(hand);
  }
  // Every device opened before the first tick and closed after the last, as hapticd does: a driver
  // port (a vendor's runtime, its stand-in) reads nothing until it is started.
  for (std::uint32_t p = 0; p < ports; ++p) {
    if (devices[p].device->start() != runtime::DeviceStatus::kOk) {
      for (std::uint32_t q = 0; q < p; ++q) devices[q].device->stop();
      throw std::invalid_argument("port " + std::to_string(p) + ": the device (" +
                                  devices[p].device->description().name + ") did not start");
    }
  }
  struct StopDevices {
    std::vector<config::PortDevice>& devices;
    ~StopDevices() {
      for (auto& d : devices) d.device->stop();
    }
  } stop_devices{devices};
  runtime::SceneExchange scenes(std::make_unique<const engine::CompiledScene>(engine::compile_scene(
      description, 50, 1, period_s, config.session_force_budget(), ports)));
  runtime::LoopCounters counters;
  runtime::TickConfig tick;
  tick.period_s = period_s;
  std::vector<runtime::TickPort> tick_ports = config::tick_ports(config, devices, ring_pointers, period_s);
  if (adjust_ports) adjust_ports(tick_ports);
  runtime::TickRunner runner(tick_ports, scenes, counters, tick);

  RunSummary summary;
  std::vector<double> last_power(ports, 0.0), given_j(ports, 0.0), taken_j(ports, 0.0);
  std::vector<JointState> joints(ports);
  const auto ticks = static_cast<std::uint64_t>(std::llround(duration_s / period_s));
  bool go_on = true;
  const auto period_ns = static_cast<std::int64_t>(std::llround(period_s * 1e9));
  const std::int64_t spin_ns = static_cast<std::int64_t>(config.real_time().spin_us()) * 1000;  // hapticd's
  const std::int64_t start_ns = device_time.real_time ? runtime::monotonic_now_ns() + period_ns : 0;
  for (std::uint64_t k = 1; k <= ticks && go_on; ++k) {
    if (device_time.real_time) {
      const std::int64_t deadline = start_ns + static_cast<std::int64_t>(k - 1) * period_ns;
      if (runtime::sleep_then_spin_until(deadline, spin_ns) > deadline + period_ns / 2) {
        ++summary.late_ticks;
      }
    }
    // The plants' state now is what this tick's reading sees (the tick advances them after).
    for (std::uint32_t p = 0; p < ports; ++p) joints[p] = plant_joints(devices[p].simulated);
    const auto time_ns = static_cast<std::int64_t>(std::llround(static_cast<double>(k - 1) * period_s * 1e9));
    if (device_time.step_device) device_time.step_device();
    runner.run(k, time_ns);
    summary.ticks = k;
    for (std::uint32_t p = 0; p < ports; ++p) {
      TickRecord record;
      record.port = p;
      record.ticks = ticks;
      runtime::TickSample& s = record.sample;
      if (!rings[p]->read(k, s)) continue;
      // The force's power on the tool, and the torque's on the handle (zero but on a 6-DOF port).
      const double power = engine::dot(s.F_T_W, s.v_WT) + engine::dot(s.tau_T_W, s.w_WT);
      const double work = k > 1 ? 0.5 * (last_power[p] + power) * period_s : 0.0;  // trapezoidal
      (work > 0.0 ? given_j[p] : taken_j[p]) += std::abs(work);
      last_power[p] = power;
      if (s.flags & (wire::kFlagForceFault | wire::kFlagDeviceFault)) ++summary.fault_ticks;
      record.energy_to_device_j = given_j[p];
      record.energy_from_device_j = taken_j[p];
      record.joints = joints[p];
      // The loop publishes the last good reading when a plant fails, so its joints tell.
      bool finite = engine::is_finite(s.p_WT) && engine::is_finite(s.v_WT) && engine::is_finite(s.F_T_W);
      for (std::uint32_t j = 0; j < record.joints.count; ++j) {
        finite = finite && std::isfinite(record.joints.q[j]) && std::isfinite(record.joints.q_dot[j]);
      }
      summary.finite = summary.finite && finite;
      if (!on_tick(record)) go_on = false;
    }
  }
  for (std::uint32_t p = 0; p < ports; ++p) {
    summary.energy_to_device += given_j[p];
    summary.energy_from_device += taken_j[p];
  }
  return summary;
}

RunSummary run_scene(const v1::ServerConfig& config, double duration_s, std::ostream& trace,
                     const std::function<void(std::uint64_t tick, std::uint64_t ticks)>& progress) {
  const std::streamsize precision = trace.precision();
  bool header_written = false;
  auto header = [&] {
    // Every value round-trips (max_digits10), so a trace reproduces a figure to the last bit.
    trace.precision(std::numeric_limits<double>::max_digits10);
    trace << "port,tick,time_s,x_m,y_m,z_m,vx_m_s,vy_m_s,vz_m_s,fx_n,fy_n,fz_n,proxy_x_m,proxy_y_m,"
             "proxy_z_m,contacts,flags,energy_to_device_j,energy_from_device_j,q0,q1,q2,q0_dot,"
             "q1_dot,q2_dot,qw,qx,qy,qz,tau_x_nm,tau_y_nm,tau_z_nm\n";
    header_written = true;
  };
  const RunSummary summary = simulate_scene(config, duration_s, [&](const TickRecord& r) {
    if (!header_written) header();  // after validation, so a refused scene writes nothing
    const runtime::TickSample& s = r.sample;
    trace << r.port << ',' << s.tick << ',' << static_cast<double>(s.time_ns) * 1e-9 << ',' << s.p_WT.x << ','
          << s.p_WT.y << ',' << s.p_WT.z << ',' << s.v_WT.x << ',' << s.v_WT.y << ',' << s.v_WT.z << ','
          << s.F_T_W.x << ',' << s.F_T_W.y << ',' << s.F_T_W.z << ',' << s.p_WP.x << ',' << s.p_WP.y
          << ',' << s.p_WP.z << ',' << s.contact_count << ',' << s.flags << ',' << r.energy_to_device_j << ','
          << r.energy_from_device_j;
    for (std::uint32_t j = 0; j < 3; ++j) {
      trace << ',';
      if (j < r.joints.count) trace << r.joints.q[j];
    }
    for (std::uint32_t j = 0; j < 3; ++j) {
      trace << ',';
      if (j < r.joints.count) trace << r.joints.q_dot[j];
    }
    // The tool's orientation (identity where the device measures none) and the torque on it.
    trace << ',' << s.R_WT.w << ',' << s.R_WT.x << ',' << s.R_WT.y << ',' << s.R_WT.z << ',' << s.tau_T_W.x
          << ',' << s.tau_T_W.y << ',' << s.tau_T_W.z << '\n';
    if (progress && r.port == 0 && (s.tick % 1000 == 0 || s.tick == r.ticks)) progress(s.tick, r.ticks);
    return true;
  });
  if (!header_written) header();  // a run shorter than one tick
  trace.precision(precision);
  return summary;
}

}  // namespace haptic::lab
