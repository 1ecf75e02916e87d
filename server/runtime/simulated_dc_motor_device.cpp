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
  description_.capabilities.measured_rates = true;
  description_.dof = 1;
  description_.joints = 1;
  description_.workspace_min = {-params.l, -params.l, 0.0};
  description_.workspace_max = {params.l, params.l, 0.0};
  description_.max_force = max_force;
  // Along the link's tangent: the tool speed is l r θ̇_m, and a force F there reaches the motor
  // through the gearbox as (r / η) l F (eq. 3.8's load, and DcMotorModel's command the same way),
  // so J_eff θ̈_m = (r / η) l F gives the tool's acceleration (l r)² F / (η J_eff):
  // m = η J_eff / (l r)², and the motor's damping B (with the back-EMF) reflects the same way.
  // (The energy argument J_eff θ̇_m² / 2 = m v² / 2 would give J_eff / (l r)², 1/η too much: the
  // gearbox's loss is no inertia, but it scales every force that crosses it.)
  const double arm = params.l * params.r;
  description_.apparent_mass = params.eta * params.J_eff() / (arm * arm);
  description_.apparent_damping = params.eta * params.B() / (arm * arm);
  description_.simulated = true;
}

DeviceStatus SimulatedDcMotorDevice::read(DeviceReading& reading) {
  reading.q[0] = plant_.state().theta_m;
  reading.q_dot[0] = plant_.state().omega_m;
  return std::isfinite(reading.q[0]) && std::isfinite(reading.q_dot[0]) ? DeviceStatus::kOk
                                                                       : DeviceStatus::kError;
}

std::uint32_t SimulatedDcMotorDevice::plant_joints(JointVector& q, JointVector& q_dot) const {
  q[0] = plant_.params().r * plant_.state().theta_m;
  q_dot[0] = plant_.params().r * plant_.state().omega_m;
  return 1;
}

DeviceStatus SimulatedDcMotorDevice::write(const DeviceCommand& command, double dt) {
  double t = 0.0;
  const engine::HandInput& hand = hand_.begin_tick(t);
  const engine::DcMotorParams& p = plant_.params();
  // A non-finite command is a fault: this tick runs with no motor torque.
  const bool command_ok = std::isfinite(command.tau[0]);
  const double u_m = command_ok ? p.R_m / p.k_m * command.tau[0] : 0.0;
  plant_.step(u_m, dt, [&](double th, double om) {
    engine::Vec3 p_WT, v_WT;
    engine::dc_motor_end_point(p, th, om, p_WT, v_WT);
    return engine::ExternalWrench{engine::hand_force(hand, p_WT, v_WT, t), {}};
  });
  hand_.end_tick(dt);
  return command_ok && std::isfinite(plant_.state().theta_m) ? DeviceStatus::kOk
                                                            : DeviceStatus::kError;
}

}  // namespace haptic::runtime
