#pragma once
// Controllers for the 1-DOF DC-motor device of engine/device/dc_motor_plant.hpp
// (Monasterio-Huelin, Gutiérrez, Larraga, "Introduction to Haptic Systems", sections 5, 6, 8, 9).
//
// The controllers compute the document's u = (k_m / R_m) u_m (eq. 5.1): a torque at the motor axis,
// Unit: N·m. voltage_from_torque_command() turns it into the plant's input u_m, which is exact for
// the model without inductance and exact in steady state (di/dt = 0) for the model with it.
// Angles and velocities are motor-side (θ_m, θ̇_m) unless named _L.

#include <cstdint>

#include "engine/device/dc_motor_plant.hpp"

namespace haptic::engine {

/// u_m = (R_m / k_m) u (eq. 5.1 inverted). u: Unit N·m; result: Unit V.
inline double voltage_from_torque_command(const DcMotorParams& p, double u) {
  return p.R_m / p.k_m * u;
}

/// Direct torque control, u = J_eff v + B θ̇_m + (r/η) τ_g(θ_m) (eq. 5.2): with a perfect model
/// the device becomes the double integrator θ̈_m = v (eq. 5.3). v: Unit rad/s². Result: Unit N·m.
double direct_torque_control(const DcMotorParams& p, double v, double theta_m, double omega_m);

/// PD position law for the linearized device, v = K_P (θ_md − θ_m) − K_D θ̇_m (eq. 5.5).
/// K_P: Unit 1/s²; K_D: Unit 1/s. Result: Unit rad/s².
inline double pd_acceleration(double K_P, double K_D, double theta_md, double theta_m,
                              double omega_m) {
  return K_P * (theta_md - theta_m) - K_D * omega_m;
}

/// Gravity compensation, u = −K_D θ̇_m + (r/η) τ_g(θ_m) (eq. 6.7): the device stops wherever it
/// is let go. K_D: Unit N·m·s/rad. Result: Unit N·m.
double gravity_compensation(const DcMotorParams& p, double K_D, double theta_m, double omega_m);

/// Weights of a sampled torsion spring-damper τ_V(k) = c1 θ_V(k) + c2 θ_V(k−1) (eqs. 8.11, 8.15).
/// Unit: N·m/rad.
struct SpringDamperCoefficients {
  double c1 = 0.0;
  double c2 = 0.0;
};

/// The exact discretization of τ_V = k_V θ_V + B_V θ̇_V (eq. 8.1) under a ZOH, made causal with a
/// one-sample delay (eqs. 8.11–8.12): with x = k_V T / B_V,
/// a1 = k_V eˣ / (eˣ − 1), a2 = −k_V / (eˣ − 1), so a1 + a2 = k_V.
/// k_V: Unit N·m/rad, > 0; B_V: Unit N·m·s/rad, > 0; T: Unit s, > 0.
SpringDamperCoefficients exact_delayed_coefficients(double k_V, double B_V, double T);

/// The Euler backward-difference discretization (eqs. 8.14–8.16): b1 = k_V + B_V / T,
/// b2 = −B_V / T. B_V may be 0.
SpringDamperCoefficients euler_backward_coefficients(double k_V, double B_V, double T);

enum class SpringDiscretization { kExactDelayed, kEulerBackward };

/// A virtual torsion spring-damper at the gearbox output with rest angle θ_L0 = r θ_m0
/// (eqs. 8.18–8.19): θ_V = r θ_m − θ_L0, hence
///   τ_V(k) = r c1 θ_m(k) + r c2 θ_m(k−1) − r (c1 + c2) θ_m0.
/// For the exact weights c1 + c2 = k_V, and this is eq. 8.19 with a = a1 — except for the rest
/// term: substituting eq. 8.18a into eq. 8.11 gives −(a1 + a2) θ_L0 = −r k_V θ_m0 (which is also
/// what eq. 9.5 carries), whereas eq. 8.19 as printed has −r a θ_m0; with that term the spring
/// would rest at θ_m = (a / k_V) θ_m0 instead of θ_m0. For the Euler weights c1 + c2 = k_V as well.
/// τ_V is the document's virtual torque, used directly as a motor-axis command in eq. 9.6.
/// Unit: N·m.
class VirtualTorsionSpring {
 public:
  VirtualTorsionSpring(const SpringDamperCoefficients& c, double r, double theta_m0);

  /// Starts a contact: the previous sample becomes theta_m_previous (θ_V(k0) = 0 when it equals
  /// θ_m0, eq. 8.11's initial condition).
  void reset(double theta_m_previous) { theta_m_previous_ = theta_m_previous; }

  /// τ_V(k) from the sample θ_m(k); remembers it for the next call.
  double torque(double theta_m) {
    const double tau =
        r_ * (c_.c1 * theta_m + c_.c2 * theta_m_previous_ - (c_.c1 + c_.c2) * theta_m0_);
    theta_m_previous_ = theta_m;
    return tau;
  }

  double theta_m0() const { return theta_m0_; }

 private:
  SpringDamperCoefficients c_;
  double r_;
  double theta_m0_;
  double theta_m_previous_;
};

/// The haptic loop of section 9: gravity compensation with a virtual torsion spring,
/// u(k) = −K_D θ̇_m(k) + (r/η) τ_g(θ_m(k)) − τ_V(k) (eq. 9.6), sampled every T and held, which in
/// continuous time gives J_eff θ̈_m + (B + K_D + r B_V) θ̇_m + r k_V θ_m − (r/η) τ_e = r k_V θ_m0
/// (eq. 9.7). θ̇_m is read from the plant (a tachometer); θ_m is sampled for the spring.
struct HapticLoopConfig {
  double K_D = 5e-3;       // Unit: N·m·s/rad.
  double k_V = 1.0;        // Unit: N·m/rad.
  double B_V = 0.02;       // Unit: N·m·s/rad.
  double T = 1e-3;         // Sampling period. Unit: s.
  double theta_m0 = 0.0;   // Spring rest angle at the motor axis. Unit: rad.
  SpringDiscretization discretization = SpringDiscretization::kExactDelayed;
};

/// u(k) of eq. 9.6 from the sampled state. Result: Unit N·m.
inline double haptic_control(const DcMotorParams& p, const HapticLoopConfig& config,
                             VirtualTorsionSpring& spring, const DcMotorState& sample) {
  return gravity_compensation(p, config.K_D, sample.theta_m, sample.omega_m) -
         spring.torque(sample.theta_m);
}

/// Builds the spring of a loop configuration; its previous sample is theta_m_previous.
VirtualTorsionSpring make_spring(const DcMotorParams& p, const HapticLoopConfig& config,
                                 double theta_m_previous);

/// Runs the loop of eq. 9.6 against the plant for `ticks` periods: sample, compute u, convert to
/// volts, hold over T while the plant integrates with the operator's wrench
/// external(theta_m, omega_m). observer(k, state, u_m) is called after every tick.
/// Allocates nothing.
template <typename ExternalWrenchFn, typename Observer>
void run_haptic_loop(DcMotorPlant& plant, const HapticLoopConfig& config, std::uint64_t ticks,
                     ExternalWrenchFn&& external, Observer&& observer) {
  const DcMotorParams& p = plant.params();
  VirtualTorsionSpring spring = make_spring(p, config, plant.state().theta_m);
  for (std::uint64_t k = 0; k < ticks; ++k) {
    const double u = haptic_control(p, config, spring, plant.state());
    const double u_m = voltage_from_torque_command(p, u);
    plant.step(u_m, config.T, external);
    observer(k, plant.state(), u_m);
  }
}

}  // namespace haptic::engine
