#include "config/devices.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <utility>

#include <google/protobuf/util/json_util.h>
#include <spdlog/spdlog.h>

#include "engine/core/rotation.hpp"
#include "schema/scene_specs.hpp"
#include "runtime/cartesian_model.hpp"
#include "runtime/dc_motor_model.hpp"
#include "runtime/driver_device.hpp"
#include "runtime/encoder_device.hpp"
#include "runtime/five_bar_estimator.hpp"
#include "runtime/five_bar_model.hpp"
#include "runtime/joystick_model.hpp"
#include "runtime/parallel_dob_model.hpp"
#include "runtime/simulated_dc_motor_device.hpp"
#include "runtime/simulated_point_mass_device.hpp"
#include "runtime/simulated_dob_device.hpp"
#include "runtime/simulated_five_bar_device.hpp"
#include "runtime/simulated_joystick_device.hpp"

namespace haptic::config {

std::string validate_integrator(const std::string& name) {
  if (name.empty() || engine::integrator_from_name(name)) return {};
  return "unknown integrator \"" + name + "\"; expected rk4, semi_implicit_euler, explicit_euler, implicit_euler or trapezoidal";
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

/// Sub-steps given (an explicit 0 too: proto3 `optional`) must be 1 to 10000; absent means 10.
template <typename DeviceConfig>
std::string check_substeps(const std::string& device, const DeviceConfig& config) {
  if (config.has_substeps() && (config.substeps() == 0 || config.substeps() > 10000)) {
    return device + ".substeps: must be 1 to 10000 (absent: 10), got " +
           std::to_string(config.substeps());
  }
  return {};
}

/// `config`'s encoders, where it sets them (`device`: "simulated_dc_motor"): noise and step lists of
/// one value or one per joint (`joints`), each finite in [0, 0.1] in the joint's unit.
template <typename DeviceConfig>
std::string validate_encoders(const DeviceConfig& config, std::size_t joints, const std::string& device) {
  if (!config.has_encoders()) return {};
  const std::string path = device + ".encoders";
  for (const auto& [values, name] : {std::pair{&config.encoders().noise(), "noise"},
                                     std::pair{&config.encoders().quantization(), "quantization"}}) {
    if (values->size() > 1 && static_cast<std::size_t>(values->size()) != joints) {
      return path + "." + name + ": give one value for every joint or one per joint (" + std::to_string(joints) +
             "), got " + std::to_string(values->size());
    }
    for (int i = 0; i < values->size(); ++i) {
      const double value = values->Get(i);
      if (!std::isfinite(value) || value < 0.0 || value > 0.1) {
        std::ostringstream out;
        out << path << "." << name << "[" << i << "]: must be finite and in [0, 0.1] (rad or m), got " << value;
        return out.str();
      }
    }
  }
  return {};
}

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
  if (auto error = check_substeps("simulated_dc_motor", motor); !error.empty()) return error;
  if (auto error = validate_integrator(motor.integrator()); !error.empty()) {
    return "simulated_dc_motor.integrator: " + error;
  }
  if (!std::isfinite(motor.max_force()) || motor.max_force() < 0.0 || motor.max_force() > 1e3) {
    return "simulated_dc_motor.max_force: must be 0 (default) to 1000";
  }
  return validate_encoders(motor, 1, "simulated_dc_motor");
}

/// The checks every simulated device's integrator and force limit share.
template <typename DeviceConfig>
std::string validate_common(const std::string& device, const DeviceConfig& config) {
  if (auto error = validate_integrator(config.integrator()); !error.empty()) {
    return device + ".integrator: " + error;
  }
  if (auto error = check_substeps(device, config); !error.empty()) return error;
  const double max_force = config.max_force();
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
  out.brakes_released = config.brakes_released();
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

namespace {

std::string check_positive(double value, double max, const std::string& path) {
  if (!std::isfinite(value) || value <= 0.0 || value > max) {
    std::ostringstream out;
    out << path << ": must be finite and in (0, " << max << "], got " << value;
    return out.str();
  }
  return {};
}

void default_vec(v1::Vec3* v, double x, double y, double z) {
  v->set_x(x);
  v->set_y(y);
  v->set_z(z);
}

std::string validate_five_bar(const v1::SimulatedFiveBarConfig& five_bar) {
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
  if (auto error = validate_encoders(five_bar, 3, "simulated_five_bar"); !error.empty()) return error;
  // Its counts are its own (quantized_encoders: π/6000 on q0 and q1, π/4000 on q2), and
  // it has no rate sensors: only the noise before the counts is the configuration's.
  if (five_bar.has_encoders() && !five_bar.encoders().quantization().empty()) {
    return "simulated_five_bar.encoders.quantization: must be empty (the five-bar's encoders count in their own "
           "steps: quantized_encoders); give noise only";
  }
  if (five_bar.has_encoders() && five_bar.encoders().tachometers()) {
    return "simulated_five_bar.encoders.tachometers: must be false (the five-bar has no rate sensors)";
  }
  return validate_common("simulated_five_bar", five_bar);
}

std::string validate_joystick(const v1::SimulatedJoystickConfig& joystick) {
  if (auto error = validate_common("simulated_joystick", joystick);
      !error.empty()) {
    return error;
  }
  if (auto error = validate_encoders(joystick, 3, "simulated_joystick"); !error.empty()) return error;
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

std::string validate_parallel_dob(const v1::SimulatedParallelDobConfig& dob, double rate) {
  if (auto error = validate_common("simulated_parallel_dob", dob);
      !error.empty()) {
    return error;
  }
  if (auto error = validate_encoders(dob, 2, "simulated_parallel_dob"); !error.empty()) return error;
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

std::string validate_driver(const v1::DriverConfig& driver) {
  if (driver.library().empty()) return "driver.library: the path of the driver's shared library is required";
  if (!driver.model().empty() && driver.model() != "cartesian") {
    return "driver.model: unknown model \"" + driver.model() + "\"; expected cartesian";
  }
  if (driver.call_timeout_ms() > 10'000) {
    return "driver.call_timeout_ms: must be 0 ... 10000, got " + std::to_string(driver.call_timeout_ms());
  }
  if (driver.stale_after() > 100'000) {
    return "driver.stale_after: must be 0 ... 100000, got " + std::to_string(driver.stale_after());
  }
  if (driver.has_profile()) {
    const v1::DeviceProfile& p = driver.profile();
    // Each axis of `v` in range (`low` itself allowed or not), or the first that is not, named.
    const auto check_axes = [](const v1::Vec3& v, const std::string& field, double low, bool low_allowed,
                               double high, const std::string& range) -> std::string {
      for (const auto& [value, axis] : {std::pair{v.x(), "x"}, std::pair{v.y(), "y"}, std::pair{v.z(), "z"}}) {
        if (!std::isfinite(value) || value < low || (!low_allowed && value <= low) || value > high) {
          return field + "." + axis + ": must be finite and in " + range + ", got " + std::to_string(value);
        }
      }
      return {};
    };
    if (auto e = check_axes(p.apparent_mass(), "driver.profile.apparent_mass", 0.0, false, 1000.0, "(0, 1000] kg");
        !e.empty()) {
      return e;
    }
    if (auto e = check_axes(p.apparent_damping(), "driver.profile.apparent_damping", 0.0, true, 1e5, "[0, 1e5] N*s/m");
        !e.empty()) {
      return e;
    }
    if (!std::isfinite(p.delay_s()) || p.delay_s() < 0.0 || p.delay_s() > 0.1) {
      return "driver.profile.delay_s: must be finite and in [0, 0.1] s, got " + std::to_string(p.delay_s());
    }
    if (!std::isfinite(p.actuator_lag_s()) || p.actuator_lag_s() < 0.0 || p.actuator_lag_s() > 0.1) {
      return "driver.profile.actuator_lag_s: must be finite and in [0, 0.1] s, got " +
             std::to_string(p.actuator_lag_s());
    }
  }
  return {};
}

/// One port's device; errors name the device's field ("simulated_joystick.substeps: ...").
std::string validate_one(const v1::DeviceConfig& device, double rate) {
  switch (device.device_case()) {
    case v1::DeviceConfig::kSimulatedPointMass:
      return validate_point_mass(device.simulated_point_mass());
    case v1::DeviceConfig::kSimulatedDcMotor:
      return validate_dc_motor(device.simulated_dc_motor());
    case v1::DeviceConfig::kSimulatedFiveBar:
      return validate_five_bar(device.simulated_five_bar());
    case v1::DeviceConfig::kSimulatedJoystick:
      return validate_joystick(device.simulated_joystick());
    case v1::DeviceConfig::kSimulatedParallelDob:
      return validate_parallel_dob(device.simulated_parallel_dob(), rate);
    case v1::DeviceConfig::kDriver:
      return validate_driver(device.driver());
    case v1::DeviceConfig::DEVICE_NOT_SET:
      break;
  }
  return "device: must set one of simulated_point_mass, simulated_dc_motor, simulated_five_bar, "
         "simulated_joystick, simulated_parallel_dob, driver";
}

double loop_rate_of(const v1::ServerConfig& config) {
  return config.loop_rate_hz() > 0.0 ? config.loop_rate_hz() : 1000.0;
}

}  // namespace

void fill_point_mass_defaults(v1::SimulatedPointMassConfig& mass) {
  if (mass.mass() == 0.0) mass.set_mass(0.01);           // Eom et al., experiment
  if (mass.damping() == 0.0) mass.set_damping(0.022);    // Eom et al., experiment
  if (!mass.has_substeps()) mass.set_substeps(10);
  // Start 20 mm above the origin, clear of a wall at z = 0 (touch_wall's).
  if (!mass.has_initial_position()) default_vec(mass.mutable_initial_position(), 0.0, 0.0, 0.02);
  if (!mass.has_workspace_min()) default_vec(mass.mutable_workspace_min(), -0.1, -0.1, -0.1);
  if (!mass.has_workspace_max()) default_vec(mass.mutable_workspace_max(), 0.1, 0.1, 0.1);
  if (mass.max_force() == 0.0) mass.set_max_force(20.0);
  if (mass.has_rotation()) {
    v1::SimulatedRotationConfig& rotation = *mass.mutable_rotation();
    // A small handle: about a 5 cm, 100 g grip's inertia, lightly damped, with the torque of a
    // desktop 6-DOF device's wrist.
    if (!rotation.has_inertia()) rotation.set_inertia(1e-4);
    if (!rotation.has_damping()) rotation.set_damping(5e-4);
    if (!rotation.has_max_torque()) rotation.set_max_torque(0.2);
  }
}

std::string validate_point_mass(const v1::SimulatedPointMassConfig& device) {
  if (device.has_sensor()) {
    for (const auto& [value, name] : {std::pair{device.sensor().noise_m(), "noise_m"},
                                      std::pair{device.sensor().quantization_m(), "quantization_m"}}) {
      if (!std::isfinite(value) || value < 0.0 || value > 0.01) {
        return std::string("simulated_point_mass.sensor.") + name + ": must be finite and in [0, 0.01] m, got " +
               std::to_string(value);
      }
    }
  }
  if (auto e = check_positive(device.mass(), 1e3, "simulated_point_mass.mass"); !e.empty()) return e;
  if (!std::isfinite(device.damping()) || device.damping() < 0.0) {
    return "simulated_point_mass.damping: must be finite and >= 0";
  }
  if (auto error = check_substeps("simulated_point_mass", device); !error.empty()) return error;
  if (auto e = check_positive(device.max_force(), 1e4, "simulated_point_mass.max_force"); !e.empty()) {
    return e;
  }
  if (!std::isfinite(device.coulomb()) || device.coulomb() < 0.0 || device.coulomb() > device.max_force()) {
    return "simulated_point_mass.coulomb: must be finite and in [0, max_force], got " + std::to_string(device.coulomb());
  }
  if (!std::isfinite(device.actuator_lag()) || device.actuator_lag() < 0.0 || device.actuator_lag() > 0.1) {
    return "simulated_point_mass.actuator_lag: must be finite and in [0, 0.1] s, got " +
           std::to_string(device.actuator_lag());
  }
  const auto& lo = device.workspace_min();
  const auto& hi = device.workspace_max();
  if (!(lo.x() < hi.x() && lo.y() < hi.y() && lo.z() < hi.z())) {
    return "simulated_point_mass.workspace_min: must be below workspace_max on every axis";
  }
  const auto& p0 = device.initial_position();
  if (p0.x() < lo.x() || p0.x() > hi.x() || p0.y() < lo.y() || p0.y() > hi.y() ||
      p0.z() < lo.z() || p0.z() > hi.z()) {
    return "simulated_point_mass.initial_position: must lie inside the workspace";
  }
  if (device.has_rotation()) {
    const v1::SimulatedRotationConfig& rotation = device.rotation();
    const std::string path = "simulated_point_mass.rotation";
    if (auto e = check_positive(rotation.inertia(), 1e3, path + ".inertia"); !e.empty()) return e;
    if (!std::isfinite(rotation.damping()) || rotation.damping() < 0.0) {
      return path + ".damping: must be finite and >= 0";
    }
    if (auto e = check_positive(rotation.max_torque(), 1e3, path + ".max_torque"); !e.empty()) return e;
    if (rotation.has_initial_orientation()) {
      const v1::Quaternion& q = rotation.initial_orientation();
      const engine::Quat R{q.w(), q.x(), q.y(), q.z()};
      if (!engine::is_unit(R, 1e-3)) return path + ".initial_orientation: must be a unit quaternion";
    }
  }
  return {};
}

v1::DeviceConfig primary_device(const v1::ServerConfig& config) {
  v1::DeviceConfig out;
  if (config.has_driver()) {
    *out.mutable_driver() = config.driver();
  } else if (config.has_simulated_dc_motor()) {
    *out.mutable_simulated_dc_motor() = config.simulated_dc_motor();
  } else if (config.has_simulated_five_bar()) {
    *out.mutable_simulated_five_bar() = config.simulated_five_bar();
  } else if (config.has_simulated_joystick()) {
    *out.mutable_simulated_joystick() = config.simulated_joystick();
  } else if (config.has_simulated_parallel_dob()) {
    *out.mutable_simulated_parallel_dob() = config.simulated_parallel_dob();
  } else {
    *out.mutable_simulated_point_mass() = config.simulated_point_mass();
  }
  return out;
}

std::string validate_device(const v1::ServerConfig& config) {
  const int devices = int{config.has_simulated_dc_motor()} + int{config.has_simulated_five_bar()} +
                      int{config.has_simulated_joystick()} +
                      int{config.has_simulated_parallel_dob()} + int{config.has_driver()};
  if (devices > 1) {
    return "simulated_dc_motor, simulated_five_bar, simulated_joystick, simulated_parallel_dob, "
           "driver: at most one device may be configured, got " + std::to_string(devices);
  }
  if (config.has_driver() && config.driver().clock() == v1::DriverConfig::DEVICE &&
      config.time_mode() == v1::LOCKSTEP) {
    return "driver.clock: DEVICE (the driver's servo loop paces the ticks) needs time_mode "
           "REAL_TIME; in LOCKSTEP the Step RPC paces them";
  }
  const double rate = loop_rate_of(config);
  if (auto error = validate_one(primary_device(config), rate); !error.empty()) return error;
  if (config.extra_devices_size() > kMaxExtraDevices) {
    return "extra_devices: at most " + std::to_string(kMaxExtraDevices) + " extra devices, got " +
           std::to_string(config.extra_devices_size());
  }
  for (int i = 0; i < config.extra_devices_size(); ++i) {
    if (auto error = validate_one(config.extra_devices(i), rate); !error.empty()) {
      return "extra_devices[" + std::to_string(i) + "]." + error;
    }
    if (config.extra_devices(i).has_driver() &&
        config.extra_devices(i).driver().clock() == v1::DriverConfig::DEVICE) {
      return "extra_devices[" + std::to_string(i) + "].driver.clock: DEVICE is for port 0's "
             "driver only (one device's servo loop paces every port)";
    }
  }
  return {};
}

namespace {

PortDevice simulated(std::unique_ptr<runtime::SimulatedDevice> device,
                     std::unique_ptr<runtime::DeviceModel> model) {
  runtime::SimulatedDevice* raw = device.get();
  return {std::move(device), std::move(model), raw, nullptr};
}

/// Joint `i`'s value of an encoder list: its one value for every joint, its i-th, or 0 past its end.
double joint_value(const google::protobuf::RepeatedField<double>& values, std::size_t i) {
  if (values.size() == 1) return values.Get(0);
  return static_cast<int>(i) < values.size() ? values.Get(static_cast<int>(i)) : 0.0;
}

/// `port`'s device read through `config`'s encoders (validated) where it sets them; the simulated
/// device's plant and operator stay reachable through port.simulated.
template <typename DeviceConfig>
PortDevice through_encoders(PortDevice port, const DeviceConfig& config, double loop_rate_hz) {
  if (!config.has_encoders()) return port;
  const v1::SimulatedEncoderConfig& encoders = config.encoders();
  runtime::EncoderOptions options;
  for (std::size_t i = 0; i < runtime::kMaxJoints; ++i) {
    options.encoder.noise[i] = joint_value(encoders.noise(), i);
    options.encoder.quantization[i] = joint_value(encoders.quantization(), i);
  }
  options.encoder.seed = encoders.seed();
  options.tachometers = encoders.tachometers();
  options.period_s = 1.0 / loop_rate_hz;
  port.device = std::make_unique<runtime::EncoderDevice>(std::move(port.device), options);
  return port;
}

PortDevice driver_device(const v1::DriverConfig& config, int thread_priority) {
  runtime::DriverOptions options;
  options.thread_priority = thread_priority;
  options.library = config.library();
  std::string params;
  if (!google::protobuf::util::MessageToJsonString(config.params(), &params).ok()) params = "{}";
  options.params_json = params;
  options.call_timeout_s = (config.has_call_timeout_ms() ? config.call_timeout_ms() : 20) * 1e-3;
  options.stale_after = config.has_stale_after() ? config.stale_after() : 3;
  options.device_clocked = config.clock() == v1::DriverConfig::DEVICE;
  if (config.has_profile()) {
    const v1::DeviceProfile& p = config.profile();
    options.profile = runtime::DriverOptions::Profile{
        {p.apparent_mass().x(), p.apparent_mass().y(), p.apparent_mass().z()},
        {p.apparent_damping().x(), p.apparent_damping().y(), p.apparent_damping().z()},
        p.delay_s(), p.actuator_lag_s()};
  }
  options.log = [library = config.library()](int level, const std::string& message) {
    const auto severity = level >= HAPTIC_DRIVER_LOG_ERROR     ? spdlog::level::err
                          : level == HAPTIC_DRIVER_LOG_WARNING ? spdlog::level::warn
                                                               : spdlog::level::info;
    spdlog::log(severity, "driver \"{}\": {}", library, message);
  };
  auto device = std::make_unique<runtime::DriverDevice>(options);
  runtime::ServoClock* servo = options.device_clocked ? device.get() : nullptr;
  return {std::move(device), std::make_unique<runtime::CartesianModel>(), nullptr, servo};
}

}  // namespace

PortDevice make_device(const v1::DeviceConfig& config, double loop_rate_hz, int driver_thread_priority) {
  switch (config.device_case()) {
    case v1::DeviceConfig::kDriver:
      return driver_device(config.driver(), driver_thread_priority);
    case v1::DeviceConfig::kSimulatedDcMotor: {
      const auto& motor = config.simulated_dc_motor();
      const engine::DcMotorParams params = dc_motor_params(motor);
      auto device = std::make_unique<runtime::SimulatedDcMotorDevice>(
          params,
          motor.with_inductance() ? engine::DcMotorModel::kWithInductance
                                  : engine::DcMotorModel::kWithoutInductance,
          motor.initial_angle(), motor.max_force() > 0.0 ? motor.max_force() : 5.0,
          integration_settings(motor.integrator(), motor.substeps(), 10));
      const bool gravity = device->description().capabilities.gravity;
      return through_encoders(simulated(std::move(device), std::make_unique<runtime::DcMotorModel>(params, gravity)),
                              motor, loop_rate_hz);
    }
    case v1::DeviceConfig::kSimulatedFiveBar: {
      const auto& five_bar = config.simulated_five_bar();
      runtime::SimulatedFiveBarOptions options;
      options.plant.integration = integration_settings(five_bar.integrator(), five_bar.substeps(), 10);
      options.plant.coriolis = !five_bar.has_coriolis() || five_bar.coriolis();
      options.plant.flexible_mode = five_bar.flexible_mode();  // FiveBarFlexibleMode's defaults
      options.quantized = !five_bar.has_quantized_encoders() || five_bar.quantized_encoders();
      if (five_bar.max_force() > 0.0) options.max_force = five_bar.max_force();
      options.state_estimator = five_bar.velocity() == "estimator";
      if (five_bar.has_encoders()) {
        for (std::size_t i = 0; i < 3; ++i) options.encoder_noise[i] = joint_value(five_bar.encoders().noise(), i);
        options.noise_seed = five_bar.encoders().seed();
      }
      const engine::FiveBarParams params = five_bar_params(five_bar);
      auto model = std::make_unique<runtime::FiveBarModel>(params, options.velocity_cutoff);
      if (options.state_estimator) {
        model->set_velocity_estimator(std::make_unique<runtime::FiveBarStateEstimators>(1.0 / loop_rate_hz));
      }
      return simulated(
          std::make_unique<runtime::SimulatedFiveBarDevice>(params, engine::FiveBarState{}, options),
          std::move(model));
    }
    case v1::DeviceConfig::kSimulatedJoystick: {
      const runtime::SimulatedJoystickConfig joystick = joystick_config(config.simulated_joystick());
      return through_encoders(simulated(std::make_unique<runtime::SimulatedJoystickDevice>(joystick),
                                        std::make_unique<runtime::JoystickModel>(joystick.model())),
                              config.simulated_joystick(), loop_rate_hz);
    }
    case v1::DeviceConfig::kSimulatedParallelDob: {
      const auto& dob = config.simulated_parallel_dob();
      const engine::Parallel2DofParams plant = parallel_params(dob);
      const engine::DisturbanceObserverParams observer = observer_params(dob, loop_rate_hz);
      const engine::Vec3 initial{0.0, 0.25, 0.0};
      const bool observer_enabled = !dob.has_disturbance_observer() || dob.disturbance_observer();
      return through_encoders(
          simulated(std::make_unique<runtime::SimulatedDobDevice>(
                        plant, initial, dob.max_force() > 0.0 ? dob.max_force() : 10.0, observer_enabled,
                        observer.nominal_mass, observer.nominal_damping),
                    std::make_unique<runtime::ParallelDobModel>(plant, observer, initial, observer_enabled)),
          dob, loop_rate_hz);
    }
    case v1::DeviceConfig::kSimulatedPointMass:
    case v1::DeviceConfig::DEVICE_NOT_SET:
      break;
  }
  // The point mass (its defaults filled by the configuration's loader).
  const v1::SimulatedPointMassConfig& mass = config.simulated_point_mass();
  engine::PointMassParams params;
  params.mass = mass.mass();
  params.damping = mass.damping();
  params.substeps = mass.substeps();
  params.coulomb = mass.coulomb();
  params.actuator_lag = mass.actuator_lag();
  params.workspace_min = schema::to_engine(mass.workspace_min());
  params.workspace_max = schema::to_engine(mass.workspace_max());
  std::optional<runtime::SimulatedRotation> rotation;
  if (mass.has_rotation()) {
    const v1::SimulatedRotationConfig& config_rotation = mass.rotation();
    rotation.emplace();
    rotation->params.inertia = config_rotation.inertia();
    rotation->params.damping = config_rotation.damping();
    rotation->params.substeps = params.substeps;
    rotation->max_torque = config_rotation.max_torque();
    if (config_rotation.has_initial_orientation()) {
      const v1::Quaternion& q = config_rotation.initial_orientation();
      rotation->initial.R_WT = engine::normalized(engine::Quat{q.w(), q.x(), q.y(), q.z()});
    }
  }
  std::optional<engine::PositionSensorParams> sensor;
  if (mass.has_sensor()) {
    sensor = engine::PositionSensorParams{mass.sensor().noise_m(), mass.sensor().quantization_m(), mass.sensor().seed()};
  }
  return simulated(std::make_unique<runtime::SimulatedPointMassDevice>(
                       params, engine::PointMassState{schema::to_engine(mass.initial_position()), {}},
                       mass.max_force(), rotation, sensor),
                   std::make_unique<runtime::CartesianModel>());
}

int driver_thread_priority(const v1::ServerConfig& config) {
  const bool fifo = config.time_mode() != v1::LOCKSTEP && config.real_time().use_fifo();
  return fifo ? config.real_time().fifo_priority() : 0;
}

PortDevice make_device(const v1::ServerConfig& config) {
  return make_device(primary_device(config), loop_rate_of(config), driver_thread_priority(config));
}

std::vector<PortDevice> make_devices(const v1::ServerConfig& config) {
  std::vector<PortDevice> out;
  out.push_back(make_device(config));
  for (const v1::DeviceConfig& extra : config.extra_devices()) {
    out.push_back(make_device(extra, loop_rate_of(config), driver_thread_priority(config)));
  }
  return out;
}

std::vector<runtime::TickPort> tick_ports(const v1::ServerConfig& config,
                                          const std::vector<PortDevice>& devices,
                                          const std::vector<runtime::SampleRing*>& rings,
                                          double period_s) {
  std::vector<runtime::TickPort> ports;
  for (std::size_t i = 0; i < devices.size(); ++i) {
    runtime::Device& device = *devices[i].device;
    runtime::TickPort port{&device, devices[i].model.get(), rings[i], {}, std::nullopt};
    port.limits = engine::force_limits_for(device.description().max_force);
    const v1::PassivityConfig& passivity = config.passivity();
    const double device_mass = device.description().apparent_mass;
    const bool passivity_on = passivity.has_enabled() ? passivity.enabled() : device_mass > 0.0;
    if (passivity_on) {
      const double threshold =
          passivity.velocity_threshold() > 0.0 ? passivity.velocity_threshold() : 1e-4;
      engine::PassivityControllerParams params = engine::passivity_params_for_device(
          device_mass > 0.0 ? device_mass : 0.01, period_s, threshold);
      if (passivity.max_damping() > 0.0) params.max_damping = passivity.max_damping();
      port.passivity = params;
    }
    ports.push_back(port);
  }
  return ports;
}

DesignDevice scene_design_device(const std::vector<PortDevice>& devices) {
  DesignDevice design;
  for (std::size_t i = 0; i < devices.size(); ++i) {
    const runtime::DeviceDescription& d = devices[i].device->description();
    if (!(d.apparent_mass > 0.0)) {  // one unknown: all unknown
      DesignDevice unknown;
      if (devices.size() > 1) {
        unknown.unknown_reason = "port " + std::to_string(i) + "'s device (" + d.name +
                                 ") does not, and objects are designed for every port";
      }
      return unknown;
    }
    const bool weaker = design.port < 0 || d.apparent_damping < design.damping ||
                        (d.apparent_damping == design.damping && d.apparent_mass < design.mass);
    if (weaker) {
      design.mass = d.apparent_mass;
      design.damping = d.apparent_damping;
      design.port = static_cast<int>(i);
      design.name = "port " + std::to_string(i) + "'s device (" + d.name + ")";
      design.unknown_reason = devices.size() > 1 ? design.name + " does not, and objects are designed for every port"
                                                 : "this one does not";
    }
  }
  return design;
}

}  // namespace haptic::config
