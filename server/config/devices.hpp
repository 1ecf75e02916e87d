#pragma once
// The simulated devices a configuration can ask for, built from their configuration messages:
// port 0's from ServerConfig's top-level device fields, ports 1.. from extra_devices.

#include <memory>
#include <string>
#include <vector>

#include "engine/device/dc_motor_plant.hpp"
#include "engine/operator/simulated_hand.hpp"
#include "haptic/v1/config.pb.h"
#include "runtime/device.hpp"
#include "runtime/device_model.hpp"
#include "runtime/servo_clock.hpp"
#include "runtime/simulated_device.hpp"
#include "runtime/tick_runner.hpp"

namespace haptic::config {

/// Empty when `name` is "" (the default, RK4) or an integrator's name, else what is wrong.
std::string validate_integrator(const std::string& name);

/// The integrator a device's configuration asks for; `substeps` 0 takes `default_substeps`.
/// `name` must have passed validate_integrator.
engine::IntegrationSettings integration_settings(const std::string& name, std::uint32_t substeps,
                                                 std::uint32_t default_substeps);

/// Document 000's parameters from the configuration (defaults where unset).
engine::DcMotorParams dc_motor_params(const v1::SimulatedDcMotorConfig& config);

/// Most extra device ports a server may have (ports 1..kMaxExtraDevices).
inline constexpr int kMaxExtraDevices = 7;

/// Fills the point mass's unset fields with their defaults (Eom et al.'s experiment).
void fill_point_mass_defaults(v1::SimulatedPointMassConfig& mass);

/// Empty when the (defaulted) point mass is valid, else "simulated_point_mass.<field>: <what>".
std::string validate_point_mass(const v1::SimulatedPointMassConfig& mass);

/// Empty when every configured device (port 0's and extra_devices') is physically possible, else
/// "<field>: <what is wrong>", an extra device's prefixed with "extra_devices[i].".
/// loop_rate_hz 0 is taken as its default.
std::string validate_device(const v1::ServerConfig& config);

/// Port 0's device as a DeviceConfig: the point mass unless one of simulated_dc_motor,
/// simulated_five_bar, simulated_joystick or simulated_parallel_dob is present.
v1::DeviceConfig primary_device(const v1::ServerConfig& config);

/// One port's device and the model the loop runs it with.
struct PortDevice {
  std::unique_ptr<runtime::Device> device;
  std::unique_ptr<runtime::DeviceModel> model;
  /// The same device when it is simulated (its operator, its plant's true state), else nullptr.
  runtime::SimulatedDevice* simulated = nullptr;
  /// A driver whose servo loop paces the ticks (DriverConfig.clock DEVICE), else nullptr.
  runtime::ServoClock* servo = nullptr;
};

/// The device `config` names (one must be set), for a loop at `loop_rate_hz` (Hz); a driver's
/// call thread asks for SCHED_FIFO at `driver_thread_priority` where > 0.
PortDevice make_device(const v1::DeviceConfig& config, double loop_rate_hz, int driver_thread_priority = 0);

/// The priority a driver port's call thread asks for: the loop's (real_time.fifo_priority) in
/// real time with use_fifo, else 0 (normal scheduling: in lockstep, or with FIFO turned off).
int driver_thread_priority(const v1::ServerConfig& config);

/// Port 0's device: make_device(primary_device(config), loop rate).
PortDevice make_device(const v1::ServerConfig& config);

/// Every device port's device, port 0 first, then extra_devices in order.
std::vector<PortDevice> make_devices(const v1::ServerConfig& config);

/// The device model the scene's objects are designed and validated for (virtual coupling gains,
/// transparency-optimal damping, the net layer's SceneLimits) when several ports render one scene:
/// the least damped, then the lightest, of them, so that a design that holds for it holds on every
/// port (Colgate's bound b > K T/2 + |B| only gets easier with more device damping). If any port's
/// device gives no mass-damper model (apparent_mass 0), none is known (all 0) and the designs
/// that need one are refused, naming the reason.
struct DesignDevice {
  double mass = 0.0;     // Unit: kg. 0: unknown.
  double damping = 0.0;  // Unit: N*s/m.
  int port = -1;         // The port whose device it is; -1 when unknown.
  std::string name;      // "port 1's device (<its description name>)"; "" when unknown.
  /// Why a design that needs the model cannot have it: "this one does not" for one port,
  /// "port 2's device (<name>) does not" when another port's device lacks it.
  std::string unknown_reason = "this one does not";
};
DesignDevice scene_design_device(const std::vector<PortDevice>& devices);

/// The loop's view of every port: its device, its sample ring, its force limit and, as the
/// configuration's `passivity` asks (by default where the device gives its mass), its passivity
/// controller. rings[i] belongs to devices[i]. Shared by hapticd and haptic-lab.
std::vector<runtime::TickPort> tick_ports(const v1::ServerConfig& config,
                                          const std::vector<PortDevice>& devices,
                                          const std::vector<runtime::SampleRing*>& rings,
                                          double period_s);

}  // namespace haptic::config
