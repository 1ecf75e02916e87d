#pragma once
// The exact step of a mass-damper under a held force, shared by the point-mass plant and the
// rigid body's rotation (the same equation with inertia for mass and torque for force).

namespace haptic::engine {

/// One axis of m v' = F − b v over h with F constant (Eom et al. eq. 5), solved exactly. With
/// a = b/m and z = a h:
///   v1 = v0 e^{−z} + (F/m) h φ(z),            φ(z) = (1 − e^{−z}) / z,
///   x1 = x0 + v0 h φ(z) + (F/m) h² g(z),      g(z) = (z − 1 + e^{−z}) / z².
/// This is the textbook form v0 e + (F/b)(1 − e), x0 + (F/b) h + (v0 − F/b)(1 − e)/a regrouped so
/// that nothing divides by b and the large terms (F/b) h and (F/b)(1 − e)/a never cancel; b = 0
/// is the limit φ = 1, g = 1/2. x, v: Unit m and m/s (rad and rad/s for a rotation).
struct ExactMassDamperStep {
  double h = -1.0;  // the step they are for (s); -1: none yet
  double decay = 1.0;
  double phi = 1.0;
  double g = 0.5;

  /// The weights for mass (or inertia) m > 0, damping b ≥ 0 and step h > 0 (s).
  static ExactMassDamperStep of(double m, double b, double h);

  /// x1 − x0 for v0 and the acceleration F/m, without applying it (a rotation composes it).
  double displacement(double v, double accel) const { return h * (v * phi + accel * h * g); }
  void advance(double& x, double& v, double accel) const {
    x += displacement(v, accel);
    v = v * decay + accel * h * phi;
  }
};

}  // namespace haptic::engine
