#include "runtime/simulated_device.hpp"

namespace haptic::runtime {

SimulatedPointMassDevice::SimulatedPointMassDevice(const engine::PointMassParams& params,
                                                   const engine::PointMassState& initial,
                                                   double max_force)
    : plant_(params, initial) {
  description_.name = "simulated point mass (3-DOF mass-damper)";
  description_.model = "point_mass";
  description_.dof = 3;
  description_.workspace_min = params.workspace_min;
  description_.workspace_max = params.workspace_max;
  description_.max_force = max_force;
  description_.apparent_mass = params.mass;
  description_.apparent_damping = params.damping;
  description_.simulated = true;
}

DeviceStatus SimulatedPointMassDevice::read(DeviceReading& reading) {
  reading.p_WT = plant_.state().p_WT;
  reading.v_WT = plant_.state().v_WT;
  return engine::is_finite(reading.p_WT) && engine::is_finite(reading.v_WT) ? DeviceStatus::kOk
                                                                            : DeviceStatus::kError;
}

DeviceStatus SimulatedPointMassDevice::write(const DeviceCommand& command, double dt) {
  // A non-finite command is a fault: this tick runs with no device force.
  const bool command_ok = engine::is_finite(command.F_T_W);
  const engine::Vec3 F_device = command_ok ? command.F_T_W : engine::Vec3{};
  double t = 0.0;
  const engine::HandInput& hand = hand_.begin_tick(t);
  plant_.set_added_mass(engine::hand_mass(hand));
  // The hand is sampled per sub-step, at the sub-step's start time.
  const double h = dt / static_cast<double>(plant_.params().substeps);
  plant_.step(F_device, dt, [&](const engine::Vec3& p_WT, const engine::Vec3& v_WT) {
    const engine::Vec3 F_hand = engine::hand_force(hand, p_WT, v_WT, t);
    t += h;
    return F_hand;
  });
  hand_.end_tick(dt);
  return command_ok && engine::is_finite(plant_.state().p_WT) ? DeviceStatus::kOk
                                                              : DeviceStatus::kError;
}

}  // namespace haptic::runtime
