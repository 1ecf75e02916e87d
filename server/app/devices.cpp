#include "app/devices.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "net/validation.hpp"
#include "runtime/five_bar_estimator.hpp"
#include "runtime/simulated_dc_motor_device.hpp"
#include "runtime/simulated_device.hpp"
#include "runtime/simulated_dob_device.hpp"
#include "runtime/simulated_five_bar_device.hpp"
#include "runtime/simulated_joystick_device.hpp"

namespace haptic::app {

std::string validate_integrator(const std::string& name) {
  if (name.empty() || engine::integrator_from_name(name)) return {};
  return "unknown integrator \"" + name + "\"; expected rk4, semi_implicit_euler or explicit_euler";
}

engine::IntegrationSettings integration_settings(const std::string& name, std::uint32_t substeps,
                                                 std::uint32_t default_substeps) {
  engine::IntegrationSettings settings;
  settings.method = name.empty() ? engine::Integrator::kRk4 : *engine::integrator_from_name(name);
  settings.substeps = substeps > 0 ? substeps : default_substeps;
  return settings;
}

engine::DcMotorParams dc_motor_params(const v1::SimulatedDcMotorConfig& config) {
  engine::DcMotorParams params;
  if (config.has_r()) params.r = config.r();
  if (config.has_eta()) params.eta = config.eta();
  if (config.has_link_mass()) params.m = config.link_mass();
  if (config.has_link_length()) params.l = config.link_length();
  if (config.has_center_of_mass()) params.l_c = config.center_of_mass();
  if (config.has_gravity()) params.g = config.gravity();
  // The link as a uniform rod of its length and mass (as the defaults assume).
  params.I_zz = params.m * params.l * params.l / 12.0;
  return params;
}

namespace {

std::string validate_dc_motor(const v1::SimulatedDcMotorConfig& motor) {
  if (auto error = dc_motor_params(motor).validate(); !error.empty()) {
    // Name the configuration's field rather than the model's symbol.
    static const std::pair<const char*, const char*> kNames[] = {
        {"r:", "r"}, {"eta:", "eta"}, {"m:", "link_mass"}, {"l:", "link_length"},
        {"l_c:", "center_of_mass"}, {"g:", "gravity"}, {"I_zz:", "link_mass"}};
    for (const auto& [symbol, field] : kNames) {
      if (error.rfind(symbol, 0) == 0) {
        return "simulated_dc_motor." + std::string(field) + error.substr(std::string(symbol).size() - 1);
      }
    }
    return "simulated_dc_motor: " + error;
  }
  if (!std::isfinite(motor.initial_angle())) return "simulated_dc_motor.initial_angle: must be finite";
  if (motor.substeps() > 10000) return "simulated_dc_motor.substeps: must be 0 (default) to 10000";
  if (auto error = validate_integrator(motor.integrator()); !error.empty()) {
    return "simulated_dc_motor.integrator: " + error;
  }
  if (!std::isfinite(motor.max_force()) || motor.max_force() < 0.0 || motor.max_force() > 1e3) {
    return "simulated_dc_motor.max_force: must be 0 (default) to 1000";
  }
  return {};
}

/// The checks every simulated device's integrator and force limit share.
std::string validate_common(const std::string& device, const std::string& integrator,
                            std::uint32_t substeps, double max_force) {
  if (auto error = validate_integrator(integrator); !error.empty()) {
    return device + ".integrator: " + error;
  }
  if (substeps > 10000) return device + ".substeps: must be 0 (default) to 10000";
  if (!std::isfinite(max_force) || max_force < 0.0 || max_force > 1e3) {
    return device + ".max_force: must be 0 (default) to 1000";
  }
  return {};
}

engine::FiveBarParams five_bar_params(const v1::SimulatedFiveBarConfig& config) {
  return config.inertias() == "theoretical" ? engine::FiveBarParams::theoretical()
                                            : engine::FiveBarParams::identified();
}

runtime::SimulatedJoystickConfig joystick_config(const v1::SimulatedJoystickConfig& config) {
  runtime::SimulatedJoystickConfig out;
  out.integration = integration_settings(config.integrator(), config.substeps(), 10);
  if (config.max_force() > 0.0) out.max_force = config.max_force();
  // Negative: never re-arm on its own (the device's 0).
  if (config.has_rearm_after_s()) out.rearm_after_s = std::max(0.0, config.rearm_after_s());
  if (config.initial_shaft_length() != 0.0) out.initial.R = config.initial_shaft_length();
  return out;
}

engine::DisturbanceObserverParams observer_params(const v1::SimulatedParallelDobConfig& config,
                                                  double loop_rate_hz) {
  engine::DisturbanceObserverParams out;
  if (config.has_nominal_mass()) out.nominal_mass = config.nominal_mass();
  if (config.has_nominal_damping()) out.nominal_damping = config.nominal_damping();
  if (config.cutoff_hz() != 0.0) out.cutoff = 2.0 * std::numbers::pi * config.cutoff_hz();
  out.sample_period = 1.0 / loop_rate_hz;
  return out;
}

engine::Parallel2DofParams parallel_params(const v1::SimulatedParallelDobConfig& config) {
  engine::Parallel2DofParams out;
  out.integration = integration_settings(config.integrator(), config.substeps(), 10);
  return out;
}

}  // namespace

std::string validate_device(const v1::ServerConfig& config) {
  const int devices = int{config.has_simulated_dc_motor()} + int{config.has_simulated_five_bar()} +
                      int{config.has_simulated_joystick()} +
                      int{config.has_simulated_parallel_dob()};
  if (devices > 1) {
    return "simulated_dc_motor, simulated_five_bar, simulated_joystick, simulated_parallel_dob: "
           "at most one device may be configured, got " + std::to_string(devices);
  }
  if (config.has_simulated_dc_motor()) return validate_dc_motor(config.simulated_dc_motor());
  if (config.has_simulated_five_bar()) {
    const auto& five_bar = config.simulated_five_bar();
    if (!five_bar.velocity().empty() && five_bar.velocity() != "difference" &&
        five_bar.velocity() != "estimator") {
      return "simulated_five_bar.velocity: must be \"difference\" or \"estimator\", got \"" +
             five_bar.velocity() + "\"";
    }
    if (!five_bar.inertias().empty() && five_bar.inertias() != "identified" &&
        five_bar.inertias() != "theoretical") {
      return "simulated_five_bar.inertias: must be \"identified\" or \"theoretical\", got \"" +
             five_bar.inertias() + "\"";
    }
    return validate_common("simulated_five_bar", five_bar.integrator(), five_bar.substeps(),
                           five_bar.max_force());
  }
  if (config.has_simulated_joystick()) {
    const auto& joystick = config.simulated_joystick();
    if (auto error = validate_common("simulated_joystick", joystick.integrator(),
                                     joystick.substeps(), joystick.max_force());
        !error.empty()) {
      return error;
    }
    if (joystick.has_rearm_after_s() && !std::isfinite(joystick.rearm_after_s())) {
      return "simulated_joystick.rearm_after_s: must be finite";
    }
    if (auto error = joystick_config(joystick).validate(); !error.empty()) {
      if (error.rfind("initial.R:", 0) == 0) {
        return "simulated_joystick.initial_shaft_length" + error.substr(std::string("initial.R").size());
      }
      return "simulated_joystick: " + error;
    }
    return {};
  }
  if (config.has_simulated_parallel_dob()) {
    const auto& dob = config.simulated_parallel_dob();
    if (auto error = validate_common("simulated_parallel_dob", dob.integrator(), dob.substeps(),
                                     dob.max_force());
        !error.empty()) {
      return error;
    }
    const double rate = config.loop_rate_hz() > 0.0 ? config.loop_rate_hz() : 1000.0;
    if (!std::isfinite(dob.cutoff_hz()) || dob.cutoff_hz() < 0.0 || dob.cutoff_hz() >= rate / 2.0) {
      return "simulated_parallel_dob.cutoff_hz: must be 0 (default) or below half the loop rate (" +
             std::to_string(rate / 2.0) + " Hz), got " + std::to_string(dob.cutoff_hz());
    }
    if (auto error = observer_params(dob, rate).validate(); !error.empty()) {
      return "simulated_parallel_dob." + error;
    }
    if (auto error = parallel_params(dob).validate(); !error.empty()) {
      return "simulated_parallel_dob: " + error;
    }
    return {};
  }
  return {};
}

SimulatedDevice make_device(const v1::ServerConfig& config) {
  SimulatedDevice out;
  if (config.has_simulated_dc_motor()) {
    const auto& motor = config.simulated_dc_motor();
    auto device = std::make_unique<runtime::SimulatedDcMotorDevice>(
        dc_motor_params(motor),
        motor.with_inductance() ? engine::DcMotorModel::kWithInductance
                                : engine::DcMotorModel::kWithoutInductance,
        motor.initial_angle(), motor.max_force() > 0.0 ? motor.max_force() : 5.0,
        integration_settings(motor.integrator(), motor.substeps(), 10));
    auto* raw = device.get();
    out.set_hand = [raw](const engine::HandInput& hand) { raw->set_hand(hand); };
    out.device = std::move(device);
    return out;
  }
  const double rate_hz = config.loop_rate_hz() > 0.0 ? config.loop_rate_hz() : 1000.0;
  if (config.has_simulated_five_bar()) {
    const auto& five_bar = config.simulated_five_bar();
    runtime::SimulatedFiveBarOptions options;
    options.plant.integration = integration_settings(five_bar.integrator(), five_bar.substeps(), 10);
    options.plant.coriolis = !five_bar.has_coriolis() || five_bar.coriolis();
    options.plant.flexible_mode = five_bar.flexible_mode();  // FiveBarFlexibleMode's defaults
    options.quantized = !five_bar.has_quantized_encoders() || five_bar.quantized_encoders();
    if (five_bar.max_force() > 0.0) options.max_force = five_bar.max_force();
    auto device = std::make_unique<runtime::SimulatedFiveBarDevice>(five_bar_params(five_bar),
                                                                     engine::FiveBarState{}, options);
    if (five_bar.velocity() == "estimator") {
      device->set_velocity_estimator(std::make_unique<runtime::FiveBarStateEstimators>(1.0 / rate_hz));
    }
    auto* raw = device.get();
    out.set_hand = [raw](const engine::HandInput& hand) { raw->set_hand(hand); };
    out.device = std::move(device);
    return out;
  }
  if (config.has_simulated_joystick()) {
    auto device =
        std::make_unique<runtime::SimulatedJoystickDevice>(joystick_config(config.simulated_joystick()));
    auto* raw = device.get();
    out.set_hand = [raw](const engine::HandInput& hand) { raw->set_hand(hand); };
    out.device = std::move(device);
    return out;
  }
  if (config.has_simulated_parallel_dob()) {
    const auto& dob = config.simulated_parallel_dob();
    auto device = std::make_unique<runtime::SimulatedDobDevice>(
        parallel_params(dob), observer_params(dob, rate_hz), engine::Vec3{0.0, 0.25, 0.0},
        dob.max_force() > 0.0 ? dob.max_force() : 10.0,
        !dob.has_disturbance_observer() || dob.disturbance_observer());
    auto* raw = device.get();
    out.set_hand = [raw](const engine::HandInput& hand) { raw->set_hand(hand); };
    out.device = std::move(device);
    return out;
  }
  const auto& mass = config.simulated_point_mass();
  engine::PointMassParams params;
  params.mass = mass.mass();
  params.damping = mass.damping();
  params.substeps = mass.substeps();
  params.workspace_min = net::to_engine(mass.workspace_min());
  params.workspace_max = net::to_engine(mass.workspace_max());
  auto device = std::make_unique<runtime::SimulatedPointMassDevice>(
      params, engine::PointMassState{net::to_engine(mass.initial_position()), {}}, mass.max_force());
  auto* raw = device.get();
  out.set_hand = [raw](const engine::HandInput& hand) { raw->set_hand(hand); };
  out.device = std::move(device);
  return out;
}

}  // namespace haptic::app
