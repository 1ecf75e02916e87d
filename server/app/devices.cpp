#include "app/devices.hpp"

#include <cmath>
#include <utility>

#include "net/validation.hpp"
#include "runtime/simulated_dc_motor_device.hpp"
#include "runtime/simulated_device.hpp"

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

std::string validate_device(const v1::ServerConfig& config) {
  if (!config.has_simulated_dc_motor()) return {};
  const auto& motor = config.simulated_dc_motor();
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
