#pragma once
// The shaft axis's force servo (Russo 1990, §4.2.1, Fig. 4.4, L886–L902): the desired force fed
// forward through an estimate K_t* of the transmission ratio, plus proportional feedback of the
// error between the desired and the measured (load-cell) force. Its static output is eq. 4.2,
//   F_out = F_des (K_t / K_t* + K_p K_t) / (1 + K_p K_t),
// which tends to F_des as K_p K_t grows, however wrong K_t* is.

namespace haptic::engine {

struct ForceServoParams {
  double transmission_estimate = 1.0;  // K_t*: output force per unit command, as believed. > 0.
  double gain = 0.0;                   // K_p: command per unit force error. >= 0.
};

/// The command u = F_des / K_t* + K_p (F_des − F_measured). Units: forces in N; u in the
/// actuator's command unit (the transmission maps u to K_t u newtons).
inline double force_servo_command(const ForceServoParams& p, double desired, double measured) {
  return desired / p.transmission_estimate + p.gain * (desired - measured);
}

/// Eq. 4.2: F_out / F_des at rest through a transmission whose true ratio is K_t (N per command
/// unit). Dimensionless.
inline double static_force_gain(const ForceServoParams& p, double transmission) {
  return (transmission / p.transmission_estimate + p.gain * transmission) /
         (1.0 + p.gain * transmission);
}

}  // namespace haptic::engine
