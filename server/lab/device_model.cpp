#include "lab/device_model.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "config/server_config.hpp"
#include "config/devices.hpp"

namespace haptic::lab {
namespace {

using Matrix = std::array<std::array<double, 3>, 3>;

/// The inverse of a 3×3 matrix by cofactors; false when it is singular to working precision.
bool invert(const Matrix& a, Matrix& inverse) {
  const double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                     a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                     a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  double scale = 0.0;
  for (const auto& row : a) {
    for (double v : row) scale = std::max(scale, std::abs(v));
  }
  if (!std::isfinite(det) || std::abs(det) <= 1e-12 * scale * scale * scale) return false;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      // Cofactor of a[j][i] (the adjugate is the transposed cofactor matrix).
      const int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
      inverse[i][j] = (a[r0][c0] * a[r1][c1] - a[r0][c1] * a[r1][c0]) / det;
    }
  }
  return true;
}

/// Diagonal of J⁻ᵀ A J⁻¹: a joint-space inertia (kg·m², kg) or damping (N·m·s/rad, N·s/m) seen at
/// the tool along each axis of W with the other axes held. Units: kg or N·s/m.
std::array<double, 3> at_tool(const Matrix& j_inverse, const Matrix& joint_space) {
  std::array<double, 3> diagonal{};
  for (int axis = 0; axis < 3; ++axis) {
    double sum = 0.0;  // Σ_ab (J⁻¹)_a,axis A_ab (J⁻¹)_b,axis
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) sum += j_inverse[a][axis] * joint_space[a][b] * j_inverse[b][axis];
    }
    diagonal[axis] = sum;
  }
  return diagonal;
}

/// Fills `model` from a joint-space inertia and damping and the tip Jacobian (see the header).
void from_joint_space(const Matrix& jacobian, const Matrix& inertia, const Matrix& damping,
                      const std::string& where, DeviceModel& model) {
  Matrix j_inverse{};
  if (!invert(jacobian, j_inverse)) {
    throw std::invalid_argument(where + ": the tool Jacobian is singular at the initial pose, so the "
                                "device has no apparent mass there; move the initial pose or give "
                                "--mass and --damping");
  }
  model.method = "jacobian";
  model.axis_mass = at_tool(j_inverse, inertia);
  model.axis_damping = at_tool(j_inverse, damping);
  int best = 0;
  for (int axis = 1; axis < 3; ++axis) {
    const bool less_damped = model.axis_damping[axis] < model.axis_damping[best];
    const bool as_damped_lighter = model.axis_damping[axis] == model.axis_damping[best] &&
                                   model.axis_mass[axis] < model.axis_mass[best];
    if (less_damped || as_damped_lighter) best = axis;
  }
  model.axis = best;
  model.mass = model.axis_mass[best];
  model.damping = model.axis_damping[best];
}

}  // namespace

DeviceModel device_model(const v1::ServerConfig& given, const std::string& source) {
  v1::ServerConfig config = given;
  config::fill_defaults(config);
  if (auto error = config::validate(config); !error.empty()) {
    throw std::invalid_argument(source + ": " + error);
  }
  std::vector<config::PortDevice> devices = config::make_devices(config);
  const runtime::Device& device = *devices.front().device;
  const runtime::SimulatedDevice* simulated = devices.front().simulated;
  const runtime::DeviceDescription& description = device.description();
  DeviceModel model;
  model.source = source;
  model.name = description.name;
  model.model = description.model;
  model.loop_rate_hz = config.loop_rate_hz();
  const std::string where = source + ": device \"" + description.model + "\"";
  if (description.apparent_mass > 0.0) {
    model.method = "description";
    model.mass = description.apparent_mass;
    model.damping = description.apparent_damping;
  } else if (const auto dynamics =
                 simulated != nullptr ? simulated->joint_space_dynamics() : std::nullopt) {
    from_joint_space(dynamics->jacobian, dynamics->inertia, dynamics->damping, where, model);
  } else {
    throw std::invalid_argument(where + " gives no apparent mass at its tool point; give --mass and "
                                "--damping instead of --device");
  }
  if (!(std::isfinite(model.mass) && model.mass > 0.0)) {
    throw std::invalid_argument(where + ": apparent mass must be finite and > 0 kg, got " +
                                std::to_string(model.mass));
  }
  if (!(std::isfinite(model.damping) && model.damping >= 0.0)) {
    throw std::invalid_argument(where + ": apparent damping must be finite and >= 0 N*s/m, got " +
                                std::to_string(model.damping));
  }
  return model;
}

DeviceModel device_model_from_file(const std::string& path) {
  v1::ServerConfig config;
  try {
    config = config::load_config_file(path);
  } catch (const config::ConfigError& error) {
    throw std::invalid_argument(std::string("--device: ") + error.what());
  }
  return device_model(config, path);
}

std::optional<DeviceModel> apply_device_arguments(const DeviceArguments& arguments, double& mass_kg,
                                                  double& damping_n_s_m, double& period_s) {
  if (arguments.device_path.empty()) return std::nullopt;
  if (arguments.mass_given || arguments.damping_given) {
    const std::string given = arguments.mass_given && arguments.damping_given ? "--mass and --damping"
                              : arguments.mass_given                          ? "--mass"
                                                                              : "--damping";
    throw std::invalid_argument("--device and " + given +
                                " were both given: take the device model either from a configuration "
                                "(--device) or by hand (--mass, --damping), not both");
  }
  DeviceModel model = device_model_from_file(arguments.device_path);
  mass_kg = model.mass;
  damping_n_s_m = model.damping;
  if (!arguments.period_given) period_s = 1.0 / model.loop_rate_hz;
  return model;
}

void require_device_model(double mass_kg, double damping_n_s_m, double period_s) {
  const auto fail = [](const std::string& what, double value) {
    std::ostringstream out;
    out << what << ", got " << value;
    throw std::invalid_argument(out.str());
  };
  if (!(std::isfinite(mass_kg) && mass_kg >= 1e-6 && mass_kg <= 1e3)) {
    fail("mass: must be 1e-6 to 1000 kg", mass_kg);
  }
  if (!(std::isfinite(damping_n_s_m) && damping_n_s_m >= 0.0)) {
    fail("damping: must be finite and >= 0 N*s/m", damping_n_s_m);
  }
  if (!(std::isfinite(period_s) && period_s >= 1e-4 && period_s <= 1e-2)) {
    fail("period: must be 1e-4 to 0.01 s (hapticd's loops run at 100 to 10000 Hz)", period_s);
  }
}

std::string describe(const DeviceModel& model) {
  std::ostringstream out;
  out << "Device model from `" << model.source << "`: " << model.name << " (" << model.model << ") at "
      << model.loop_rate_hz << " Hz; m = " << model.mass << " kg, b = " << model.damping << " N·s/m";
  if (model.method == "jacobian") {
    static const char* kAxes[] = {"x", "y", "z"};
    out << " along " << kAxes[model.axis] << " of W at the initial pose (J⁻ᵀ D J⁻¹ and J⁻ᵀ B J⁻¹, "
        << "the least damped, then lightest, axis; per axis x, y, z: m = " << model.axis_mass[0] << ", "
        << model.axis_mass[1] << ", " << model.axis_mass[2] << " kg, b = " << model.axis_damping[0]
        << ", " << model.axis_damping[1] << ", " << model.axis_damping[2] << " N·s/m)";
  } else {
    out << " (the device's own apparent mass and damping)";
  }
  out << ".\n";
  return out.str();
}

}  // namespace haptic::lab
