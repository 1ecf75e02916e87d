#include "runtime/simulated_dc_motor_device.hpp"

#include <cmath>

namespace haptic::runtime {

SimulatedDcMotorDevice::SimulatedDcMotorDevice(const engine::DcMotorParams& params,
                                               engine::DcMotorModel model, double initial_theta_L,
                                               double max_force,
                                               engine::IntegrationSettings integration)
    : plant_(params, model, engine::DcMotorState{initial_theta_L / params.r, 0.0, 0.0},
             integration) {
  description_.name = model == engine::DcMotorModel::kWithInductance
                          ? "simulated 1-DOF DC motor, gearbox and link (000, with inductance)"
                          : "simulated 1-DOF DC motor, gearbox and link (000, without inductance)";
  description_.model = "dc_motor_000";
  description_.capabilities.gravity = params.g != 0.0;
  description_.dof = 1;
  description_.workspace_min = {-params.l, -params.l, 0.0};
  description_.workspace_max = {params.l, params.l, 0.0};
  description_.max_force = max_force;
  // Along the link's tangent: the tool speed is l r θ̇_m, so J_eff θ̇_m² / 2 = m v² / 2 gives
  // m = J_eff / (l r)², and the motor's damping B (with the back-EMF) reflects the same way.
  const double arm = params.l * params.r;
  description_.apparent_mass = params.J_eff() / (arm * arm);
  description_.apparent_damping = params.B() / (arm * arm);
  description_.simulated = true;
}

void SimulatedDcMotorDevice::tool_state(double theta_m, double omega_m, engine::Vec3& p_WT,
                                        engine::Vec3& v_WT) const {
  const engine::DcMotorParams& p = plant_.params();
  const double phi = p.r * theta_m + p.alpha_c;
  const double omega_L = p.r * omega_m;
  p_WT = {p.l * std::cos(phi), p.l * std::sin(phi), 0.0};
  v_WT = {-p.l * std::sin(phi) * omega_L, p.l * std::cos(phi) * omega_L, 0.0};
}

DeviceStatus SimulatedDcMotorDevice::read(DeviceReading& reading) {
  tool_state(plant_.state().theta_m, plant_.state().omega_m, reading.p_WT, reading.v_WT);
  return std::isfinite(reading.p_WT.x) && std::isfinite(reading.v_WT.x) ? DeviceStatus::kOk
                                                                         : DeviceStatus::kError;
}

DeviceStatus SimulatedDcMotorDevice::write(const DeviceCommand& command, double dt) {
  double t = 0.0;
  const engine::HandInput& hand = hand_.begin_tick(t);
  const engine::DcMotorParams& p = plant_.params();
  const double theta_m = plant_.state().theta_m;
  // A non-finite command is a fault: this tick runs with no device force (gravity stays compensated).
  const bool command_ok = engine::is_finite(command.F_T_W);
  const double tau_d =
      command_ok ? engine::external_joint_torque(p, p.r * theta_m, {command.F_T_W, {}}) : 0.0;
  // A device declared without gravity (g = 0: a horizontal link) skips the cosine altogether.
  const double tau_g = description_.capabilities.gravity ? p.gravity_torque(theta_m) : 0.0;
  const double u_m = p.R_m / p.k_m * (p.r / p.eta) * (tau_g + tau_d);
  plant_.step(u_m, dt, [&](double th, double om) {
    engine::Vec3 p_WT, v_WT;
    tool_state(th, om, p_WT, v_WT);
    return engine::ExternalWrench{engine::hand_force(hand, p_WT, v_WT, t), {}};
  });
  hand_.end_tick(dt);
  return command_ok && std::isfinite(plant_.state().theta_m) ? DeviceStatus::kOk
                                                            : DeviceStatus::kError;
}

}  // namespace haptic::runtime
