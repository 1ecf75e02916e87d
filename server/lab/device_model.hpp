#pragma once
// The device model `haptic-lab zwidth` and `transparency` analyse, taken from a hapticd
// configuration: the device at its tool point as a mass-damper along one axis, and the loop rate.
//
// Where the device gives that model itself (DeviceDescription::apparent_mass: the point mass,
// 000's DC motor, 001's device behind its disturbance observer) it is used as given. The five-bar
// (003) and the joystick (004) give none, because their tool-point inertia depends on the pose;
// for them it is computed here at the configured initial pose, per Cartesian axis of W:
//   M_x = J⁻ᵀ D(q) J⁻¹,  B_x = J⁻ᵀ B_q J⁻¹
// (the joint-space inertia and viscous friction seen through the tip Jacobian v_WT = J q̇, with
// the other axes held), and the axis analysed is the one with the least damping, then the least
// mass: Colgate's passivity bound b > K T/2 + |B| (Madill eq. 2.6) is tightest where b is
// smallest, and with b small the sampled loop's stiffness limit grows with m / T².

#include <array>
#include <optional>
#include <string>

#include "haptic/v1/config.pb.h"

namespace haptic::lab {

struct DeviceModel {
  std::string source;  // The configuration file or label it came from.
  std::string name;    // DeviceDescription::name.
  std::string model;   // DeviceDescription::model ("five_bar_003", …).
  double mass = 0.0;     // Apparent mass at the tool point along `axis`. Unit: kg. > 0.
  double damping = 0.0;  // Apparent viscous damping there. Unit: N·s/m. ≥ 0.
  double loop_rate_hz = 1000.0;  // The configuration's loop rate. Unit: Hz.
  /// How the mass-damper was obtained: "description" (the device's own) or "jacobian" (above).
  std::string method;
  int axis = -1;  // The axis of W analysed (0 x, 1 y, 2 z); -1 when the device gives one value.
  /// The jacobian method's per-axis values (diagonals of M_x and B_x). Units: kg, N·s/m.
  std::array<double, 3> axis_mass{}, axis_damping{};
};

/// Port 0's device of `config` (defaults filled in and validated first, as `haptic-lab run`
/// does). `source` names the configuration in messages. Throws std::invalid_argument naming
/// the configuration's first invalid field, or saying that the device gives no apparent mass.
DeviceModel device_model(const v1::ServerConfig& config, const std::string& source);

/// Loads `path` (a hapticd configuration, JSON) and calls device_model. Throws
/// std::invalid_argument naming the file on any error.
DeviceModel device_model_from_file(const std::string& path);

/// What a command line said about the device model: --device's path (empty: not given) and
/// whether --mass, --damping and --period were given explicitly.
struct DeviceArguments {
  std::string device_path;
  bool mass_given = false;
  bool damping_given = false;
  bool period_given = false;
};

/// With a device path: loads the model and writes its mass (kg) and damping (N·s/m) into
/// `mass_kg` and `damping_n_s_m`, and, unless the period was given, 1 / loop_rate_hz into
/// `period_s` (s); returns the model. Without one: changes nothing and returns nullopt. Throws
/// std::invalid_argument naming --device and each of --mass and --damping given beside it, or
/// what device_model_from_file throws.
std::optional<DeviceModel> apply_device_arguments(const DeviceArguments& arguments, double& mass_kg,
                                                  double& damping_n_s_m, double& period_s);

/// One markdown paragraph saying where the model came from (appended to the reports).
std::string describe(const DeviceModel& model);

/// The device model's numbers as haptic-lab's studies take them: mass 1e-6 to 1000 kg, damping
/// finite and >= 0, period 1e-4 to 0.01 s (hapticd's loops run at 100 to 10000 Hz). Throws
/// std::invalid_argument naming the first that is not, and its value.
void require_device_model(double mass_kg, double damping_n_s_m, double period_s);

}  // namespace haptic::lab
