#pragma once
// The simulated devices a configuration can ask for, built from their configuration messages.

#include <functional>
#include <memory>
#include <string>

#include "engine/device/dc_motor_plant.hpp"
#include "engine/operator/simulated_hand.hpp"
#include "haptic/v1/config.pb.h"
#include "runtime/device.hpp"

namespace haptic::app {

/// Empty when `name` is "" (the default, RK4) or an integrator's name, else what is wrong.
std::string validate_integrator(const std::string& name);

/// The integrator a device's configuration asks for; `substeps` 0 takes `default_substeps`.
/// `name` must have passed validate_integrator.
engine::IntegrationSettings integration_settings(const std::string& name, std::uint32_t substeps,
                                                 std::uint32_t default_substeps);

/// Document 000's parameters from the configuration (defaults where unset).
engine::DcMotorParams dc_motor_params(const v1::SimulatedDcMotorConfig& config);

/// Empty when the configured device is physically possible, else "<field>: <what is wrong>".
std::string validate_device(const v1::ServerConfig& config);

struct SimulatedDevice {
  std::unique_ptr<runtime::Device> device;
  std::function<void(const engine::HandInput&)> set_hand;  // the simulated operator's input
};

/// The device the configuration names: the point mass unless one of simulated_dc_motor,
/// simulated_five_bar, simulated_joystick or simulated_parallel_dob is present.
SimulatedDevice make_device(const v1::ServerConfig& config);

}  // namespace haptic::app
