#include "engine/control/dc_motor_control.hpp"

#include <cassert>
#include <cmath>

namespace haptic::engine {

double direct_torque_control(const DcMotorParams& p, double v, double theta_m, double omega_m) {
  return p.J_eff() * v + p.B() * omega_m + p.r / p.eta * p.gravity_torque(theta_m);  // eq. 5.2
}

double gravity_compensation(const DcMotorParams& p, double K_D, double theta_m, double omega_m) {
  return -K_D * omega_m + p.r / p.eta * p.gravity_torque(theta_m);  // eq. 6.7
}

SpringDamperCoefficients exact_delayed_coefficients(double k_V, double B_V, double T) {
  assert(k_V > 0.0 && B_V > 0.0 && T > 0.0);
  // Eq. 8.12 with numerator and denominator multiplied by e^{−x}: a1 = k_V / (1 − e^{−x}),
  // a2 = −k_V e^{−x} / (1 − e^{−x}). This never overflows for large x, and expm1 keeps 1 − e^{−x}
  // exact to round-off as T → 0, where the weights grow like B_V / T.
  const double x = k_V * T / B_V;
  const double one_minus_decay = -std::expm1(-x);
  return {k_V / one_minus_decay, -k_V * std::exp(-x) / one_minus_decay};
}

SpringDamperCoefficients euler_backward_coefficients(double k_V, double B_V, double T) {
  assert(T > 0.0 && B_V >= 0.0);
  return {k_V + B_V / T, -B_V / T};  // eqs. 8.16a, 8.16b
}

VirtualTorsionSpring::VirtualTorsionSpring(const SpringDamperCoefficients& c, double r,
                                           double theta_m0)
    : c_(c), r_(r), theta_m0_(theta_m0), theta_m_previous_(theta_m0) {}

VirtualTorsionSpring make_spring(const DcMotorParams& p, const HapticLoopConfig& config,
                                 double theta_m_previous) {
  const SpringDamperCoefficients c =
      config.discretization == SpringDiscretization::kExactDelayed
          ? exact_delayed_coefficients(config.k_V, config.B_V, config.T)
          : euler_backward_coefficients(config.k_V, config.B_V, config.T);
  VirtualTorsionSpring spring(c, p.r, config.theta_m0);
  spring.reset(theta_m_previous);
  return spring;
}

}  // namespace haptic::engine
