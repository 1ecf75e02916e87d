#include "lab/device_zwidth.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "config/devices.hpp"
#include "config/server_config.hpp"
#include "engine/analysis/growth.hpp"
#include "lab/lab_run.hpp"
#include "schema/scene_specs.hpp"

namespace haptic::lab {
namespace {

/// The walk's step along K: 2^¼, a grid fine enough to find a device's stability changing twice.
const double kQuarterOctave = std::pow(2.0, 0.25);

/// Where the tool starts on `port`: the first tick's reading.
engine::Vec3 start_position(const v1::ServerConfig& config, std::uint32_t port, const DeviceTime& device_time) {
  engine::Vec3 start{};
  bool found = false;
  simulate_scene(config, 1.0 / config.loop_rate_hz(), [&](const TickRecord& r) {
    if (r.port == port) {
      start = r.sample.p_WT;
      found = true;
    }
    return true;
  }, {}, device_time);
  if (!found) throw std::invalid_argument("port: " + std::to_string(port) + " is not one of the configuration's ports");
  return start;
}

/// Where the `kind` of device in `devices` (a ServerConfig, its port 0's kind from
/// config::primary_device; or a DeviceConfig) is simulated and reads through noise (its point
/// mass's sensor, or its encoders, with a noise above 0), that noise's seed mixed with `run`
/// (distinct runs, distinct seeds, and unlike another port's own); whether it is. A driver's
/// hardware has noise of its own.
template <class Devices>
bool redraw_noise(Devices& devices, v1::DeviceConfig::DeviceCase kind, int run) {
  const auto mix = [run](auto& sensor) {
    sensor.set_seed(sensor.seed() ^ (static_cast<std::uint64_t>(run) * 0x9E3779B97F4A7C15ULL));
  };
  const auto encoders = [&](const auto& device, auto mutable_device) {
    const auto& noise = device.encoders().noise();
    if (!std::any_of(noise.begin(), noise.end(), [](double n) { return n > 0.0; })) return false;
    mix(*mutable_device()->mutable_encoders());
    return true;
  };
  switch (kind) {
    case v1::DeviceConfig::kSimulatedDcMotor:
      return encoders(devices.simulated_dc_motor(), [&] { return devices.mutable_simulated_dc_motor(); });
    case v1::DeviceConfig::kSimulatedFiveBar:
      return encoders(devices.simulated_five_bar(), [&] { return devices.mutable_simulated_five_bar(); });
    case v1::DeviceConfig::kSimulatedJoystick:
      return encoders(devices.simulated_joystick(), [&] { return devices.mutable_simulated_joystick(); });
    case v1::DeviceConfig::kSimulatedParallelDob:
      return encoders(devices.simulated_parallel_dob(), [&] { return devices.mutable_simulated_parallel_dob(); });
    case v1::DeviceConfig::kSimulatedPointMass:
      if (!(devices.simulated_point_mass().sensor().noise_m() > 0.0)) return false;
      mix(*devices.mutable_simulated_point_mass()->mutable_sensor());
      return true;
    default:
      return false;
  }
}

/// One run of the wall (device_wall_settles).
bool wall_run_settles(const v1::ServerConfig& given, const DeviceWallParams& params, double stiffness,
                      double damping) {
  if (std::abs(engine::norm(params.direction) - 1.0) > 1e-9) throw std::invalid_argument("direction: must be a unit vector");
  if (!(params.push_n > 0.0) || !(params.seconds > 4.0 * params.window_s) || !(params.window_s > 0.0) ||
      !(params.noise_floor_m >= 0.0) || !(params.penetration_m >= 0.0) || !(params.min_push_n >= 0.0)) {
    throw std::invalid_argument(
        "push_n > 0, seconds > 4 windows > 0, noise_floor_m >= 0, penetration_m >= 0 and min_push_n >= 0 are needed");
  }
  const double push_n = std::max(
      params.min_push_n,
      params.penetration_m > 0.0 ? std::min(params.push_n, stiffness * params.penetration_m) : params.push_n);
  v1::ServerConfig config = given;
  config::fill_defaults(config);
  if (auto e = config::validate(config); !e.empty()) throw std::invalid_argument(e);
  const engine::Vec3 start = start_position(config, params.port, params.device_time);
  // The wall: the plane through the start, outward along +axis; its law the sampled analysis's.
  config.mutable_initial_scene()->clear_objects();
  config.mutable_initial_scene()->clear_fields();
  v1::Object* wall = config.mutable_initial_scene()->add_objects();
  wall->mutable_pose()->mutable_position()->set_x(start.x);
  wall->mutable_pose()->mutable_position()->set_y(start.y);
  wall->mutable_pose()->mutable_position()->set_z(start.z);
  *wall->mutable_half_space()->mutable_normal() = schema::to_proto(params.direction);
  wall->mutable_impedance()->set_stiffness(stiffness);
  wall->mutable_impedance()->set_damping(damping);
  wall->mutable_impedance()->set_law(v1::Impedance::BACKWARD_DIFFERENCE);
  config.mutable_passivity()->set_enabled(false);
  // The push into the wall: a constant force field about the start (a linear field without a
  // gradient), so that it reaches every port as a command does, a driver's too (the simulated
  // operator pushes simulated devices only).
  config.clear_initial_operator();
  v1::LinearField* push = config.mutable_initial_scene()->add_fields()->mutable_linear();
  *push->mutable_origin() = schema::to_proto(start);
  *push->mutable_force() = schema::to_proto(-push_n * params.direction);
  for (int row = 0; row < 3; ++row) push->add_jacobian();
  push->set_radius(1.0);
  push->set_fade_width(0.5);

  const double period = 1.0 / config.loop_rate_hz();
  const double equilibrium = engine::dot(start, params.direction) - push_n / stiffness;
  const auto window = static_cast<std::size_t>(std::llround(params.window_s / period));
  std::vector<double> distance;  // from the equilibrium, along the axis. Unit: m.
  std::vector<double> along;     // the reading along the axis. Unit: m.
  bool finite = true;
  simulate_scene(config, std::round(params.seconds / period) * period, [&](const TickRecord& r) {
    if (r.port != params.port) return true;
    const double x = engine::dot(r.sample.p_WT, params.direction);
    finite = finite && std::isfinite(x);
    along.push_back(x);
    distance.push_back(std::abs(x - equilibrium));
    return finite;
  }, {}, params.device_time);
  if (!finite || distance.size() < 4 * window) return false;
  // The envelope's growth from the first window on (engine/analysis/growth): a run near the
  // boundary decays or grows slowly, and only its rate's sign tells which side it is on. A
  // floor of 1e-12 m, or the sensor's noise floor, leaves out windows that have decayed into
  // rounding or into what the sensor adds.
  const double floor = std::max(1e-12, params.noise_floor_m);
  const engine::GrowthFit growth = engine::envelope_growth(distance, period, params.window_s, params.window_s, floor);
  // A run that grew until the device's force limit held it (a limit cycle: its envelope flat, or
  // falling a little as it settles into the cycle) has not settled either: its last window stands
  // above its first, which holds the fall in from the surface.
  const auto first = std::max_element(distance.begin(), distance.begin() + static_cast<std::ptrdiff_t>(window));
  const auto last = std::max_element(distance.end() - static_cast<std::ptrdiff_t>(window), distance.end());
  if (params.noise_floor_m > 0.0) {
    // Measured through noise or a step, a run past the boundary grows into a limit cycle that the
    // force limit holds, flat but for the sensor's jitter, and a fit's slope over it proves
    // nothing; but it has grown: a wall that settles, starting at rest off its equilibrium,
    // never strays farther than it started (and the sensor's floor). A run that ends inside the
    // floor has settled, whatever its slope.
    const double reach = *std::max_element(distance.begin() + static_cast<std::ptrdiff_t>(window), distance.end());
    if (reach > 1.5 * distance.front() + params.noise_floor_m) return false;
    if (*last <= params.noise_floor_m) return true;
  }
  if (params.still_settles) {
    // Held by friction off its equilibrium: still, it has settled; a ring that grows is never still.
    const auto [low, high] = std::minmax_element(along.end() - static_cast<std::ptrdiff_t>(window), along.end());
    if (*high - *low <= params.noise_floor_m) return true;
  }
  return growth.rate_per_s < 0.0 && *last < *first;
}

}  // namespace

bool device_wall_settles(const v1::ServerConfig& config, const DeviceWallParams& params, double stiffness,
                         double damping) {
  if (params.runs < 1) throw std::invalid_argument("runs: must be >= 1, got " + std::to_string(params.runs));
  if (!wall_run_settles(config, params, stiffness, damping)) return false;
  for (int run = 1; run < params.runs; ++run) {
    v1::ServerConfig varied = config;
    if (params.vary) params.vary(varied, run);
    if (!wall_run_settles(varied, params, stiffness, damping)) return false;
  }
  return true;
}

bool redraw_sensor_noise(v1::ServerConfig& config, std::uint32_t port, int run) {
  if (port == 0) return redraw_noise(config, config::primary_device(config).device_case(), run);
  if (port > static_cast<std::uint32_t>(config.extra_devices_size())) return false;
  v1::DeviceConfig& extra = *config.mutable_extra_devices(static_cast<int>(port - 1));
  return redraw_noise(extra, extra.device_case(), run);
}

bool reads_through_noise(const v1::ServerConfig& config, std::uint32_t port) {
  v1::ServerConfig drawn = config;  // drawn anew on a copy: whether there was a noise to draw
  return redraw_sensor_noise(drawn, port, 1);
}

double device_zwidth_boundary(const v1::ServerConfig& config, const DeviceWallParams& params, double damping,
                              double guess, double tolerance) {
  if (!std::isfinite(guess) || guess <= 0.0) guess = 1000.0;
  // On the grid 2^(k/4) N/m, whatever the guess: the device's figure is the ground truth a
  // prediction is checked against, and where its stability changes more than once the walls
  // walked decide it, so they must not move with the prediction.
  double lo = std::pow(2.0, std::floor(4.0 * std::log2(guess / 16.0)) / 4.0);
  while (!device_wall_settles(config, params, lo, damping)) {
    lo /= 2.0;
    if (lo < guess * 1e-3) return 0.0;
  }
  double hi = lo * kQuarterOctave;
  while (device_wall_settles(config, params, hi, damping)) {
    lo = hi;
    hi *= kQuarterOctave;
    if (hi > guess * 1e3) return std::numeric_limits<double>::infinity();
  }
  while (hi / lo > 1.0 + tolerance) {
    const double mid = std::sqrt(lo * hi);
    (device_wall_settles(config, params, mid, damping) ? lo : hi) = mid;
  }
  return lo;
}

std::vector<double> device_settles_above(const v1::ServerConfig& config, const DeviceWallParams& params,
                                         double damping, double boundary, int count) {
  std::vector<double> settled;
  if (!(boundary > 0.0) || !std::isfinite(boundary)) return settled;
  double stiffness = boundary;
  for (int j = 1; j <= count; ++j) {
    stiffness *= kQuarterOctave;
    if (device_wall_settles(config, params, stiffness, damping)) settled.push_back(stiffness);
  }
  return settled;
}

}  // namespace haptic::lab
