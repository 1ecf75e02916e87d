#include "lab/lab_run.hpp"

#include <cmath>
#include <memory>
#include <stdexcept>
#include <vector>

#include "app/config.hpp"
#include "app/devices.hpp"
#include "haptic/wire/datagram.hpp"
#include "net/validation.hpp"
#include "runtime/loop_stats.hpp"
#include "runtime/tick_runner.hpp"

namespace haptic::lab {
namespace {

/// The configuration's own scene, as the server's session 0 would hold it (always there: no
/// ramp-in, so a run starts with the scene in place).
engine::SceneDescription initial_scene(const v1::ServerConfig& config, const net::SceneLimits& limits) {
  engine::SceneDescription description;
  std::uint64_t id = 1;
  for (int i = 0; i < config.initial_scene().objects_size(); ++i) {
    engine::ObjectEntry entry;
    entry.meta.id = id++;
    const std::string path = "initial_scene.objects[" + std::to_string(i) + "]";
    if (auto e = net::to_object_spec(config.initial_scene().objects(i), path, limits, entry.spec); !e.empty()) {
      throw std::invalid_argument(e);
    }
    description.objects.push_back(std::move(entry));
  }
  for (int i = 0; i < config.initial_scene().fields_size(); ++i) {
    engine::FieldEntry entry;
    entry.meta.id = id++;
    const std::string path = "initial_scene.fields[" + std::to_string(i) + "]";
    if (auto e = net::to_field_spec(config.initial_scene().fields(i), path, limits, entry.spec); !e.empty()) {
      throw std::invalid_argument(e);
    }
    description.fields.push_back(std::move(entry));
  }
  return description;
}

}  // namespace

RunSummary run_scene(const v1::ServerConfig& given, double duration_s, std::ostream& trace) {
  if (!(std::isfinite(duration_s) && duration_s > 0.0 && duration_s <= 3600.0)) {
    throw std::invalid_argument("duration: must be in (0, 3600] s, got " + std::to_string(duration_s));
  }
  v1::ServerConfig config = given;
  app::fill_defaults(config);
  if (auto e = app::validate(config); !e.empty()) throw std::invalid_argument(e);
  const double period_s = 1.0 / config.loop_rate_hz();

  std::vector<app::SimulatedDevice> devices = app::make_devices(config);
  const auto ports = static_cast<std::uint32_t>(devices.size());
  std::vector<std::unique_ptr<runtime::SampleRing>> rings;
  std::vector<runtime::SampleRing*> ring_pointers;
  for (std::uint32_t i = 0; i < ports; ++i) {
    rings.push_back(std::make_unique<runtime::SampleRing>());
    ring_pointers.push_back(rings.back().get());
  }
  net::SceneLimits limits;
  limits.period_s = period_s;
  limits.device_mass = devices.front().device->description().apparent_mass;
  limits.device_damping = devices.front().device->description().apparent_damping;
  const engine::SceneDescription description = initial_scene(config, limits);
  engine::HandInput hand;
  if (auto e = net::to_hand_input(config.initial_operator(), "initial_operator", limits, hand); !e.empty()) {
    throw std::invalid_argument(e);
  }
  for (auto& device : devices) {
    if (device.set_hand) device.set_hand(hand);
  }
  runtime::SceneExchange scenes(std::make_unique<const engine::CompiledScene>(engine::compile_scene(
      description, 50, 1, period_s, config.session_force_budget(), ports)));
  runtime::LoopCounters counters;
  runtime::TickConfig tick;
  tick.period_s = period_s;
  runtime::TickRunner runner(app::tick_ports(config, devices, ring_pointers, period_s), scenes, counters,
                             tick);

  trace << "port,tick,time_s,x_m,y_m,z_m,vx_m_s,vy_m_s,vz_m_s,fx_n,fy_n,fz_n,proxy_x_m,proxy_y_m,"
           "proxy_z_m,contacts,flags,energy_to_device_j,energy_from_device_j\n";
  RunSummary summary;
  std::vector<double> last_power(ports, 0.0), given_j(ports, 0.0), taken_j(ports, 0.0);
  const auto ticks = static_cast<std::uint64_t>(std::llround(duration_s / period_s));
  for (std::uint64_t k = 1; k <= ticks; ++k) {
    const auto time_ns = static_cast<std::int64_t>(std::llround(static_cast<double>(k - 1) * period_s * 1e9));
    runner.run(k, time_ns);
    for (std::uint32_t p = 0; p < ports; ++p) {
      runtime::TickSample s;
      if (!rings[p]->read(k, s)) continue;
      const double power = engine::dot(s.F_T_W, s.v_WT);
      const double work = k > 1 ? 0.5 * (last_power[p] + power) * period_s : 0.0;  // trapezoidal
      (work > 0.0 ? given_j[p] : taken_j[p]) += std::abs(work);
      last_power[p] = power;
      const bool finite = engine::is_finite(s.p_WT) && engine::is_finite(s.v_WT) && engine::is_finite(s.F_T_W);
      summary.finite = summary.finite && finite;
      if (s.flags & (wire::kFlagForceFault | wire::kFlagDeviceFault)) ++summary.fault_ticks;
      trace << p << ',' << s.tick << ',' << static_cast<double>(s.time_ns) * 1e-9 << ',' << s.p_WT.x << ','
            << s.p_WT.y << ',' << s.p_WT.z << ',' << s.v_WT.x << ',' << s.v_WT.y << ',' << s.v_WT.z << ','
            << s.F_T_W.x << ',' << s.F_T_W.y << ',' << s.F_T_W.z << ',' << s.p_WP.x << ',' << s.p_WP.y
            << ',' << s.p_WP.z << ',' << s.contact_count << ',' << s.flags << ',' << given_j[p] << ','
            << taken_j[p] << '\n';
    }
  }
  summary.ticks = ticks;
  for (std::uint32_t p = 0; p < ports; ++p) {
    summary.energy_to_device += given_j[p];
    summary.energy_from_device += taken_j[p];
  }
  return summary;
}

}  // namespace haptic::lab
