#include "lab/identify.hpp"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <limits>
#include <iomanip>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "config/server_config.hpp"
#include "engine/scene/impedance.hpp"
#include "lab/device_zwidth.hpp"
#include "lab/lab_run.hpp"
#include "schema/scene_specs.hpp"

namespace haptic::lab {
namespace {

const char* axis_name(int axis) { return axis == 0 ? "x" : axis == 1 ? "y" : "z"; }

/// A damping below zero by more than its 95 % interval: the axis gains energy, no mass-damper.
/// Within its interval of zero (a device with no viscous friction, 004's joystick), it is zero.
bool negative_damping(const engine::AxisIdentification& fit) {
  return fit.damping.value + fit.damping.half_width_95 < 0.0;
}

/// Friction that may hold the axis still through part of each period: beyond its interval, a
/// twentieth of the excitation's peak or more. The report then points to the fit in time, and the
/// Z-width check presses the walls past it (ZWidthCheck).
bool held_by_friction(const engine::AxisIdentification& fit, double amplitude_n) {
  return fit.coulomb.value - fit.coulomb.half_width_95 > 0.05 * amplitude_n;
}

/// The damping a model takes from the fit: the estimate, or 0 where it is below 0 within its interval.
double model_damping(const engine::AxisIdentification& fit) { return std::max(0.0, fit.damping.value); }

/// Walls on a device that friction holds and counts read run this many times (ZWidthCheck::runs):
/// on the device with its noise drawn anew each time, on the identified model from as many places
/// in a count, evenly spaced.
constexpr int kWallRuns = 16;

/// The noise before the counts: what the identified noise holds beyond a step's own q/√12 (the
/// reading's error, with the noise σ before a step q, has σ² + q²/12 of variance). Unit: m.
double noise_before_counts(const engine::AxisIdentification& f) {
  const double q = f.quantization_m.value_or(0.0);
  return std::sqrt(std::max(0.0, f.noise_rms_m * f.noise_rms_m - q * q / 12.0));
}

/// The identified model as a device (in lockstep): a point mass with the identified mass,
/// damping, friction and lag on every axis, 100 sub-steps a tick (the lag's and the stops' error
/// under 1 %), and a force limit of `max_force_n`. Its sensor is the identified step with the
/// noise beyond the step's own before it (noise_before_counts), or, where no step was found, the
/// identified noise.
v1::ServerConfig identified_model_config(const IdentifyResult& result, double loop_rate_hz, double max_force_n) {
  const engine::AxisIdentification& f = result.fit;
  v1::ServerConfig config;
  config.set_loop_rate_hz(loop_rate_hz);
  config.set_time_mode(v1::LOCKSTEP);
  v1::SimulatedPointMassConfig& mass = *config.mutable_simulated_point_mass();
  mass.set_mass(f.mass.value);
  mass.set_damping(model_damping(f));
  mass.set_coulomb(std::max(0.0, f.coulomb.value));
  mass.set_actuator_lag(std::clamp(f.lag.value, 0.0, 0.1));
  mass.set_substeps(100);
  // The default start, written out: a wall's runs move it across a count.
  *mass.mutable_initial_position() = schema::to_proto(engine::Vec3{0.0, 0.0, 0.02});
  mass.set_max_force(std::max(max_force_n, 2.0 * std::max(0.0, f.coulomb.value)));
  mass.mutable_sensor()->set_noise_m(std::min(0.01, f.quantization_m ? noise_before_counts(f) : f.noise_rms_m));
  mass.mutable_sensor()->set_quantization_m(std::min(0.01, f.quantization_m.value_or(0.0)));
  mass.mutable_sensor()->set_seed(1);
  return config;
}

/// The direction the tool moves in when the simulated operator pushes it along `axis` for 50 ms
/// with `force_n` from rest: the displacement's, normalised. Throws where it does not move.
engine::Vec3 direction_of_motion(const v1::ServerConfig& config, std::uint32_t port, int axis, double force_n,
                                 const DeviceTime& device_time) {
  v1::ServerConfig probe = config;
  v1::OperatorInput* push = probe.mutable_initial_operator();
  push->Clear();
  push->set_mode(v1::OperatorInput::APPLY_FORCE);
  engine::Vec3 force{};
  (axis == 0 ? force.x : axis == 1 ? force.y : force.z) = force_n;
  *push->mutable_force() = schema::to_proto(force);
  const double period = 1.0 / probe.loop_rate_hz();
  engine::Vec3 first{}, last{};
  bool started = false;
  simulate_scene(probe, std::round(0.05 / period) * period, [&](const TickRecord& r) {
    if (r.port != port) return true;
    if (!started) first = r.sample.p_WT;
    started = true;
    last = r.sample.p_WT;
    return true;
  }, {}, device_time);
  const engine::Vec3 moved = last - first;
  if (!(engine::norm(moved) > 0.0)) {
    throw std::invalid_argument("along the motion: pushed along " + std::string(axis_name(axis)) + " with " +
                                std::to_string(force_n) + " N for 50 ms, the tool did not move");
  }
  return moved * (1.0 / engine::norm(moved));
}

}  // namespace

IdentifyResult identify(const v1::ServerConfig& given, const IdentifyParams& params, const std::string& source) {
  if (params.axis < 0 || params.axis > 2) {
    throw std::invalid_argument("axis: must be x, y or z (0, 1, 2), got " + std::to_string(params.axis));
  }
  if (!(params.limits.box_half_width_m > 0.0) || !(params.limits.max_speed_m_s > 0.0)) {
    throw std::invalid_argument("box and max speed: must be > 0");
  }
  const runtime::ExcitationCentering& centering = params.centering;
  if (!(centering.stiffness >= 0.0) || !std::isfinite(centering.stiffness) || !(centering.damping >= 0.0) ||
      !std::isfinite(centering.damping)) {
    throw std::invalid_argument("centering: stiffness and damping must be finite and >= 0, got " +
                                std::to_string(centering.stiffness) + " N/m and " +
                                std::to_string(centering.damping) + " N·s/m");
  }
  v1::ServerConfig config = given;
  config::fill_defaults(config);
  if (auto e = config::validate(config); !e.empty()) throw std::invalid_argument(source + ": " + e);
  IdentifyResult result;
  result.period_s = 1.0 / config.loop_rate_hz();
  engine::MultisineParams signal = params.signal;
  signal.sample_period_s = result.period_s;
  std::string why;
  const std::optional<engine::Multisine> multisine = engine::design_multisine(signal, why);
  if (!multisine) throw std::invalid_argument(why);
  engine::Vec3 axis_W{};
  (params.axis == 0 ? axis_W.x : params.axis == 1 ? axis_W.y : axis_W.z) = 1.0;
  if (params.along_motion) axis_W = direction_of_motion(config, params.port, params.axis, signal.amplitude_n, params.device_time);
  result.direction = axis_W;
  runtime::ExcitationStage stage(*multisine, axis_W, params.limits, params.centering);

  // Whole ticks: the signal's, and one more so the last reading follows the last command.
  const auto ticks = static_cast<std::uint64_t>(std::llround(multisine->duration_s() / result.period_s)) + 1;
  result.duration_s = static_cast<double>(ticks) * result.period_s;
  std::vector<double> force, position;
  force.reserve(ticks);
  position.reserve(ticks);
  bool port_found = false;
  const RunSummary run = simulate_scene(
      config, static_cast<double>(ticks) / config.loop_rate_hz(),
      [&](const TickRecord& record) {
        if (record.port != params.port) return true;
        force.push_back(engine::dot(record.sample.F_T_W, axis_W));
        position.push_back(engine::dot(record.sample.p_WT, axis_W));
        return stage.stop() == runtime::ExcitationStage::Stop::kNone;
      },
      [&](std::vector<runtime::TickPort>& ports) {
        if (params.port >= ports.size()) return;
        ports[params.port].excitation = &stage;
        result.max_force_n = ports[params.port].limits.max_force;
        port_found = true;
      },
      params.device_time);
  if (!port_found) {
    throw std::invalid_argument("port: " + std::to_string(params.port) + " is not one of the configuration's ports");
  }
  result.start_position = stage.start_position();
  result.late_ticks = run.late_ticks;
  if (stage.stop() != runtime::ExcitationStage::Stop::kNone) {
    std::ostringstream message;
    message << "the excitation stopped at tick " << stage.stop_tick() << ": the tool ";
    if (stage.stop() == runtime::ExcitationStage::Stop::kLeftTheBox) {
      message << "left its box of ±" << params.limits.box_half_width_m * 1e3 << " mm";
    } else {
      message << "moved at " << stage.stop_speed() << " m/s, faster than " << params.limits.max_speed_m_s << " m/s";
    }
    message << "; lower the amplitude (" << signal.amplitude_n << " N) or raise f_min (" << signal.f_min_hz
            << " Hz), which sets how far the lowest harmonic carries it";
    throw std::invalid_argument(message.str());
  }
  const std::optional<engine::AxisIdentification> fit = engine::identify_axis(*multisine, force, position, why, -1.0,
                                                                                     params.max_lag_s, params.fit_method);
  if (!fit) throw std::invalid_argument(why);
  result.fit = *fit;
  try {
    const DeviceModel model = device_model(config, source);
    if (model.method == "jacobian") {
      result.model_mass = model.axis_mass[static_cast<std::size_t>(params.axis)];
      result.model_damping = model.axis_damping[static_cast<std::size_t>(params.axis)];
    } else {
      result.model_mass = model.mass;
      result.model_damping = model.damping;
    }
    result.model_method = model.method;
  } catch (const std::invalid_argument& error) {
    result.model_method = std::string("none: ") + error.what();
  }
  return result;
}

std::string identify_report(const IdentifyResult& r, const IdentifyParams& params, const std::string& source) {
  std::ostringstream out;
  out << std::setprecision(4);
  const engine::AxisIdentification& f = r.fit;
  const engine::MultisineParams& s = params.signal;
  out << "# Identification of " << source << ", port " << params.port << ", along (" << r.direction.x << ", "
      << r.direction.y << ", " << r.direction.z << ")"
      << (params.along_motion ? std::string(" (the motion under a push along ") + axis_name(params.axis) + ")" : "")
      << "\n\n"
      << "A multisine of " << f.response.size() << " harmonics from " << f.response.front().frequency_hz << " to "
      << f.response.back().frequency_hz << " Hz, " << s.amplitude_n << " N peak, " << f.periods
      << " periods fitted; " << r.duration_s << " s of " << (params.device_time.real_time ? "real-time" : "lockstep")
      << " ticks at " << 1.0 / r.period_s << " Hz. Intervals: 95 %, delete-one-period jackknife.";
  const bool in_time = f.method == engine::FitMethod::kMovingStretches;
  if (in_time) {
    out << " Fitted in time over the stretches where the axis moved one way: " << 100.0 * f.moving_fraction
        << " % of the fitted ticks (the rest friction held, or too slow to tell).";
  }
  out << "\n\n";
  if (r.late_ticks > 0) {
    // A late tick held its force longer than the fit assumes: said first, where it is read.
    out << "**" << r.late_ticks << " of " << std::llround(r.duration_s / r.period_s)
        << " ticks started more than half a period late**: each held its force longer than the fit assumes. "
           "Close other programs, give haptic-lab real-time priority (chrt -f 80), or lower the loop's rate.\n\n";
  }
  out
      << "| parameter | identified | 95 % interval | model | error |\n|---|---|---|---|---|\n";
  const auto row = [&](const char* name, const engine::Estimate& e, std::optional<double> model, const char* unit) {
    out << "| " << name << " (" << unit << ") | " << e.value << " | ± " << e.half_width_95 << " | ";
    if (model && *model != 0.0) {
      out << *model << " | " << std::showpos << 100.0 * (e.value - *model) / *model << std::noshowpos << " % |\n";
    } else if (model) {
      out << *model << " | - |\n";
    } else {
      out << "- | - |\n";
    }
  };
  row("mass", f.mass, r.model_mass, "kg");
  row("damping", f.damping, r.model_damping, "N·s/m");
  row("Coulomb friction", f.coulomb, std::nullopt, "N");
  row("constant force", f.offset, std::nullopt, "N");
  row("delay", f.delay, std::nullopt, "s");
  if (params.max_lag_s > 0.0) row("lag", f.lag, std::nullopt, "s");
  out << "\nFriction to move +: " << f.coulomb_positive << " N, −: " << f.coulomb_negative
      << " N. Delay beyond a perfect loop's (the hold's half tick): "
      << (f.delay.value - r.period_s / 2.0) * 1e3 << " ms (" << (f.delay.value - r.period_s / 2.0) / r.period_s
      << " ticks). Noise: " << f.noise_rms_m * 1e6 << " µm rms. Quantization: ";
  if (f.quantization_m) {
    out << *f.quantization_m * 1e6 << " µm";
  } else {
    out << "no lattice (the positions are not whole steps of one size)";
  }
  out << ". Residual: " << 100.0 * f.relative_residual << (in_time ? " % of the motion's rms" : " % of the force's rms")
      << ".\n\nThe model: " << r.model_method
      << ".\n";
  // A fit that is not a mass-damper's says so rather than leaving its figures to be used.
  if (!(f.mass.value > 0.0) || negative_damping(f) || f.relative_residual > 0.2) {
    out << "\n**Not a mass-damper along this direction**: "
        << (!(f.mass.value > 0.0) ? "the mass came out not positive"
            : negative_damping(f) ? "the damping came out negative, beyond its interval"
                                    : "the residual is over 20 %")
        << ". The axis is coupled to others, held by friction, or not rigid over the band: do not use these figures; "
           "try --along-motion, another amplitude or band.\n";
  }
  // Much friction beside the excitation: it may hold the axis still through part of each period,
  // where the harmonics' equation does not hold (004's joystick: its mass −51 % at a residual of
  // 4 %), so the fit in time is worth comparing.
  if (f.method == engine::FitMethod::kHarmonics && held_by_friction(f, params.signal.amplitude_n)) {
    out << "\n**The friction is " << 100.0 * f.coulomb.value / params.signal.amplitude_n
        << " % of the excitation's peak**: where it holds the axis still through part of each period, the fit at "
           "the harmonics is biased however small its residual; compare --fit moving (docs/identification.md, "
           "\"Stick and slip\").\n";
  }
  return out.str();
}

v1::DeviceProfile identify_profile(const v1::ServerConfig& config, const IdentifyParams& params, const std::string& source) {
  engine::Vec3 mass{}, damping{};
  double delay_s = 0.0, lag_s = 0.0;
  for (int axis = 0; axis < 3; ++axis) {
    IdentifyParams p = params;
    p.axis = axis;
    p.along_motion = false;
    const IdentifyResult r = identify(config, p, source);
    if (!(r.fit.mass.value > 0.0) || negative_damping(r.fit)) {
      throw std::invalid_argument(std::string("profile: along ") + axis_name(axis) + " the fit is no mass-damper (mass " +
                                  std::to_string(r.fit.mass.value) + " kg, damping " +
                                  std::to_string(r.fit.damping.value) + " N·s/m)");
    }
    (axis == 0 ? mass.x : axis == 1 ? mass.y : mass.z) = r.fit.mass.value;
    (axis == 0 ? damping.x : axis == 1 ? damping.y : damping.z) = model_damping(r.fit);
    delay_s = std::max(delay_s, r.fit.delay.value - r.period_s / 2.0);
    lag_s = std::max(lag_s, r.fit.lag.value);  // 0 unless --lag
  }
  v1::DeviceProfile profile;
  *profile.mutable_apparent_mass() = schema::to_proto(mass);
  *profile.mutable_apparent_damping() = schema::to_proto(damping);
  profile.set_delay_s(std::max(0.0, delay_s));
  profile.set_actuator_lag_s(lag_s);
  return profile;
}

std::vector<ZWidthCheck> check_zwidth(const v1::ServerConfig& config, const IdentifyParams& params,
                                      const IdentifyResult& result, const std::vector<double>& dampings,
                                      const std::function<void(std::size_t done, std::size_t total)>& progress) {
  // The lag where one was fitted (0 otherwise): the analysis samples it exactly.
  const engine::MassDamperDevice model{result.fit.mass.value, model_damping(result.fit), std::max(0.0, result.fit.lag.value)};
  if (!(model.mass > 0.0) || negative_damping(result.fit)) {
    throw std::invalid_argument("zwidth: the identified model is not a mass-damper (mass " +
                                std::to_string(model.mass) + " kg, damping " + std::to_string(model.damping) +
                                " N·s/m): no prediction from it");
  }
  // The delay beyond the hold's half tick, in ticks, fractional (the analysis interpolates).
  const double delay_ticks = std::max(0.0, (result.fit.delay.value - result.period_s / 2.0) / result.period_s);
  DeviceWallParams wall;
  wall.port = params.port;
  wall.direction = result.direction;
  wall.device_time = params.device_time;
  // A sensor with noise or a step: a run that ends within five steps of the equilibrium has
  // settled. With quantization a stable wall still rocks by a step or two about its equilibrium
  // (Diolaiti et al. 2006's limit cycles), while a wall past its Z-width grows to tens of steps.
  // The step is the lattice's where one was found, or √12 times the noise's rms where that is
  // more (what a step q alone gives: q/√12; on Gaussian noise, 17σ, above any window's largest
  // draw). Noise under a nanometre is the simulation's rounding, not a sensor's. The push holds
  // the equilibrium four floors inside the wall at every K, up to twice the excitation's peak (a
  // force the device took in free motion).
  if (result.fit.noise_rms_m > 1e-9 || result.fit.quantization_m) {
    wall.noise_floor_m = 5.0 * std::max(result.fit.quantization_m.value_or(0.0), std::sqrt(12.0) * result.fit.noise_rms_m);
    wall.penetration_m = 4.0 * wall.noise_floor_m;
    wall.push_n = std::max(wall.push_n, 2.0 * params.signal.amplitude_n);
  }
  // Held by friction (see ZWidthCheck): pressed past it, still is settled, and the prediction is
  // the identified model's own walls.
  const bool friction_held = held_by_friction(result.fit, params.signal.amplitude_n);
  std::optional<v1::ServerConfig> friction_model;
  DeviceWallParams model_wall = wall;
  if (friction_held) {
    wall.min_push_n = 2.5 * result.fit.coulomb.value;
    wall.still_settles = true;
    friction_model = identified_model_config(result, config.loop_rate_hz(), result.max_force_n);
    model_wall = wall;
    model_wall.port = 0;
    model_wall.device_time = {};
    // Read through a step as well: whether a wall settles turns on where in a count the tool
    // rests and on what the noise draws as it crosses one, so each wall runs kWallRuns times,
    // on the device with its noise drawn anew (as on a bench, run again), on the model from
    // evenly spaced places in a count; it settles where every run does.
    if (result.fit.quantization_m && reads_through_noise(config, params.port)) {
      wall.runs = kWallRuns;
      wall.vary = [port = params.port](v1::ServerConfig& device, int run) { redraw_sensor_noise(device, port, run); };
      const engine::Vec3 across_a_count = result.direction * (*result.fit.quantization_m / kWallRuns);
      model_wall.runs = kWallRuns;
      model_wall.vary = [across_a_count](v1::ServerConfig& model, int run) {
        v1::SimulatedPointMassConfig& mass = *model.mutable_simulated_point_mass();
        *mass.mutable_initial_position() =
            schema::to_proto(schema::to_engine(mass.initial_position()) + across_a_count * static_cast<double>(run));
        redraw_sensor_noise(model, 0, run);
      };
    }
  }
  std::vector<ZWidthCheck> checks;
  for (const double damping : dampings) {
    ZWidthCheck check;
    check.damping = damping;
    check.runs = wall.runs;
    const engine::ImpedanceParams law{100.0, damping, 0.0};
    const auto discretization = engine::ImpedanceDiscretization::kBackwardDifference;
    check.linear =
        engine::sampled_wall_margin(law, discretization, model, result.period_s, delay_ticks).max_stable_stiffness;
    check.predicted = check.linear;
    if (friction_model) {
      check.friction_model = true;
      check.predicted = device_zwidth_boundary(*friction_model, model_wall, damping, 3.0 * check.linear);
    }
    check.measured = device_zwidth_boundary(config, wall, damping, 3.0 * check.predicted);
    if (wall.noise_floor_m > 0.0 || friction_held) {
      check.settles_above = device_settles_above(config, wall, damping, check.measured);
    }
    if (result.model_mass && result.model_damping && *result.model_mass > 0.0) {
      check.described = engine::sampled_wall_margin(law, discretization, {*result.model_mass, *result.model_damping},
                                                    result.period_s, 0.0)
                            .max_stable_stiffness;
    }
    checks.push_back(check);
    if (progress) progress(checks.size(), dampings.size());
  }
  return checks;
}

std::string zwidth_report(const std::vector<ZWidthCheck>& checks) {
  std::ostringstream out;
  out << std::setprecision(4);
  out << "\n## Z-width: predicted against the device's own\n\n";
  if (!checks.empty() && checks.front().friction_model) {
    out << "Held by friction: the walls are pressed with 2.5 times the identified friction, a run that ends still "
           "has settled, and the prediction is the same walls on the identified model (mass, damping, friction and "
           "lag, simulated). Without the friction, the sampled analysis gives";
    for (const ZWidthCheck& c : checks) out << " " << c.linear;
    out << " N/m.\n\n";
    if (checks.front().runs > 1) {
      out << "Read through a step as well: each wall ran " << checks.front().runs
          << " times, on the device with its noise drawn anew, on the model from as many places in a count, and "
             "settled only where every run did. Where in a count the tool rests, and what the noise draws as it "
             "crosses one, decide whether such a wall rings, so one run a wall can overstate what holds.\n\n";
    }
  }
  out
      << "| B (N·s/m) | K_max measured (N/m) | predicted from the identified model | error | from the description | "
         "error |\n|---|---|---|---|---|---|\n";
  for (const ZWidthCheck& c : checks) {
    const auto error = [&](double predicted) {
      return c.measured > 0.0 && std::isfinite(c.measured) ? 100.0 * (predicted - c.measured) / c.measured : 0.0;
    };
    out << "| " << c.damping << " | " << c.measured << " | " << c.predicted << " | " << std::showpos << error(c.predicted)
        << std::noshowpos << " % | ";
    if (c.described) {
      out << *c.described << " | " << std::showpos << error(*c.described) << std::noshowpos << " % |\n";
    } else {
      out << "- | - |\n";
    }
  }
  bool said = false;
  for (const ZWidthCheck& c : checks) {
    if (c.settles_above.empty()) continue;
    if (!said) {
      out << "\nNot one boundary: walls stiffer than the first that rings settle again, so the device's stability "
             "changes more than once along K (as where friction and a sensor's counts set it, not a mass-damper). "
             "The measured figure is the first wall that rings going up; every wall under it settled.\n\n";
      said = true;
    }
    out << "- B = " << c.damping << " N·s/m: settled again at";
    for (const double k : c.settles_above) out << " " << k;
    out << " N/m.\n";
  }
  return out.str();
}

std::vector<IdentifySweepRow> identify_sweep(const v1::ServerConfig& config, const IdentifyParams& params,
                                             const std::vector<std::size_t>& periods,
                                             const std::vector<double>& amplitudes_n, const std::string& source,
                                             const std::function<void(std::size_t done, std::size_t total)>& progress) {
  std::vector<IdentifySweepRow> rows;
  const std::size_t total = periods.size() * amplitudes_n.size();
  for (const double amplitude : amplitudes_n) {
    for (const std::size_t count : periods) {
      IdentifyParams p = params;
      p.signal.amplitude_n = amplitude;
      p.signal.periods = count;
      const std::clock_t started = std::clock();
      const IdentifyResult r = identify(config, p, source);
      IdentifySweepRow row;
      row.cpu_s = static_cast<double>(std::clock() - started) / CLOCKS_PER_SEC;
      if (!r.model_mass || !r.model_damping || !(*r.model_mass > 0.0) || !(*r.model_damping >= 0.0)) {
        throw std::invalid_argument("sweep: " + source + "'s device gives no mass and damping to measure the errors against");
      }
      row.amplitude_n = amplitude;
      row.periods = count;
      row.excitation_s = r.duration_s;
      row.mass_error = std::abs(r.fit.mass.value - *r.model_mass) / *r.model_mass;
      const double no_relative = std::numeric_limits<double>::quiet_NaN();  // a model without damping
      const bool damped = *r.model_damping > 0.0;
      row.damping_error = damped ? std::abs(r.fit.damping.value - *r.model_damping) / *r.model_damping : no_relative;
      row.mass_half_width = r.fit.mass.half_width_95 / *r.model_mass;
      row.damping_half_width = damped ? r.fit.damping.half_width_95 / *r.model_damping : no_relative;
      row.damping = r.fit.damping.value;
      row.damping_half_width_abs = r.fit.damping.half_width_95;
      row.delay_half_width_s = r.fit.delay.half_width_95;
      rows.push_back(row);
      if (progress) progress(rows.size(), total);
    }
  }
  return rows;
}

std::string identify_sweep_csv(const std::vector<IdentifySweepRow>& rows) {
  std::ostringstream out;
  out << std::setprecision(std::numeric_limits<double>::max_digits10);
  out << "amplitude_n,periods,excitation_s,cpu_s,mass_error,damping_error,mass_half_width,damping_half_width,"
         "delay_half_width_s,damping_n_s_m,damping_half_width_n_s_m\n";
  for (const IdentifySweepRow& r : rows) {
    out << r.amplitude_n << ',' << r.periods << ',' << r.excitation_s << ',' << r.cpu_s << ',' << r.mass_error << ','
        << r.damping_error << ',' << r.mass_half_width << ',' << r.damping_half_width << ',' << r.delay_half_width_s
        << ',' << r.damping << ',' << r.damping_half_width_abs << '\n';
  }
  return out.str();
}

std::string identify_response_csv(const IdentifyResult& r) {
  std::ostringstream out;
  out << std::setprecision(std::numeric_limits<double>::max_digits10);
  out << "frequency_hz,measured_m_per_n,measured_phase_deg,model_m_per_n,model_phase_deg\n";
  for (const engine::FrequencyPoint& p : r.fit.response) {
    out << p.frequency_hz << ',' << std::abs(p.measured) << ',' << std::arg(p.measured) * 180.0 / std::numbers::pi
        << ',' << std::abs(p.model) << ',' << std::arg(p.model) * 180.0 / std::numbers::pi << '\n';
  }
  return out.str();
}

}  // namespace haptic::lab
