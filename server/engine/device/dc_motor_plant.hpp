#pragma once
// A 1-DOF haptic device: DC motor + reduction gearbox + rigid link under gravity
// (Monasterio-Huelin, Gutiérrez, Larraga, "Introduction to Haptic Systems", sections 2–4).
//
// Frames: W is the device's base frame (the document's S_0): z along the joint axis, x horizontal,
// y up, so gravity is −g ŷ. The load angle θ_L is measured about z from x (eq. 3.4); the motor
// angle is θ_m = θ_L / r (eq. 3.1a). E is the link's end point P_e, where the operator's force
// acts, at distance l from the axis and at the constant angle α_c from the centre of mass
// (eq. 4.2a).
// Angles in rad, angular velocities in rad/s; motor-side quantities carry the suffix _m.

#include <cmath>
#include <cstdint>
#include <string>

#include "engine/core/integrator.hpp"
#include "engine/core/vec3.hpp"

namespace haptic::engine {

/// Physical parameters of the motor, gearbox and load.
///
/// Motor defaults: maxon RE 40, Ø40 mm, graphite brushes, 150 W, part number 148877 (48 V winding),
/// maxon catalogue data sheet: nominal voltage 48 V, no-load speed 7580 rpm, no-load current
/// 69 mA, terminal resistance 1.16 Ω, terminal inductance 0.329 mH, torque constant 60.3 mN·m/A,
/// speed constant 158 rpm/V, rotor inertia 134 g·cm², mechanical time constant 4.28 ms, stall
/// torque 2500 mN·m. (Consistency check: R J / k_m² = 4.28 ms; 48 V / 1.16 Ω · k_m = 2.50 N·m.)
/// k_b follows from the speed constant: 60 / (2π · 158) = 0.06044 V·s/rad (≈ k_m, as eq. 2.4
/// notes).
/// Assumed, not on the data sheet: B_m, estimated by treating the whole no-load friction torque
/// k_m · 69 mA = 4.16 mN·m as viscous at the no-load speed 793.8 rad/s; the gearbox (a capstan-like
/// reduction r = 0.1, η = 0.9); and the load, an aluminium link of 0.2 kg and 0.2 m treated as a
/// uniform rod (l_c = 0.1 m, I_zz = m l² / 12), with the handle on the centre-of-mass line
/// (α_c = 0).
struct DcMotorParams {
  // Motor (eqs. 2.1–2.4).
  double R_m = 1.16;        // Terminal resistance. Unit: Ω.
  double L_m = 0.329e-3;    // Terminal inductance. Unit: H.
  double k_m = 60.3e-3;     // Torque constant. Unit: N·m/A.
  double k_b = 0.0604386;   // Back-EMF constant. Unit: V·s/rad.
  double J_m = 134e-7;      // Rotor inertia. Unit: kg·m².
  double B_m = 5.24e-6;     // Viscous friction (assumed, see above). Unit: N·m·s/rad.
  // Gearbox (eq. 3.1).
  double r = 0.1;           // Reduction θ̇_L / θ̇_m, in (0, 1].
  double eta = 0.9;         // Efficiency, in (0, 1].
  // Load (eqs. 3.4–3.7, 4.2a).
  double I_zz = 0.2 * 0.2 * 0.2 / 12.0;  // Inertia about the centre of mass. Unit: kg·m².
  double m = 0.2;           // Link mass. Unit: kg.
  double l_c = 0.1;         // Axis to centre of mass. Unit: m.
  double l = 0.2;           // Axis to the end point E. Unit: m.
  double alpha_c = 0.0;     // Angle from the centre-of-mass line to E. Unit: rad.
  double g = 9.81;          // Gravitational acceleration. Unit: m/s².

  /// Empty when every parameter is usable; otherwise one message naming the first bad parameter
  /// ("r: must be in (0, 1], got 1.5"). Called once, at the boundary; the plant asserts it.
  std::string validate() const;

  /// Load inertia about the joint, J_L = I_zz + m l_c² (eq. 3.7). Unit: kg·m².
  double J_L() const { return I_zz + m * l_c * l_c; }
  /// Effective inertia at the motor axis, J_eff = J_m + r² J_L / η (eq. 3.10a). Unit: kg·m².
  double J_eff() const { return J_m + r * r * J_L() / eta; }
  /// Effective damping with the back-EMF, B = B_m + k_b k_m / R_m (eq. 3.10b). Unit: N·m·s/rad.
  double B() const { return B_m + k_b * k_m / R_m; }
  /// Electrical time constant t_e = L_m / R_m (eq. 2.5a). Unit: s.
  double t_e() const { return L_m / R_m; }
  /// Mechanical time constant of the bare motor, t_m = R_m J_m / (R_m B_m + k_b k_m) (eq. 2.5b).
  /// Unit: s.
  double t_m() const { return R_m * J_m / (R_m * B_m + k_b * k_m); }
  /// Gravity torque at the load, τ_g = m g l_c cos(r θ_m) (eq. 3.10c). Unit: N·m.
  double gravity_torque(double theta_m) const { return m * g * l_c * std::cos(r * theta_m); }
};

/// The operator's wrench on the link at E, expressed in W (the document's F_e, eq. 4.2b).
struct ExternalWrench {
  Vec3 f_E_W;  // Force. Unit: N.
  Vec3 n_W;    // Moment. Unit: N·m.
};

/// Joint torque at the load from the wrench, τ_e = Jᵀ(θ_L) F_e with
/// J = [−l sin(θ_L + α_c), l cos(θ_L + α_c), 0, 0, 0, 1]ᵀ (eqs. 4.1–4.3). Unit: N·m.
double external_joint_torque(const DcMotorParams& params, double theta_L,
                             const ExternalWrench& F_e);

/// The end point E's position (m) and velocity (m/s) in W at motor angle θ_m (rad) and rate θ̇_m
/// (rad/s): p = l (cos φ, sin φ, 0), φ = r θ_m + α_c (eqs. 3.1a, 4.2a).
void dc_motor_end_point(const DcMotorParams& params, double theta_m, double omega_m, Vec3& p_WT,
                        Vec3& v_WT);

/// Plant state at the motor axis.
struct DcMotorState {
  double theta_m = 0.0;  // Motor angle. Unit: rad.
  double omega_m = 0.0;  // Motor angular velocity θ̇_m. Unit: rad/s.
  double i = 0.0;        // Armature current. Unit: A. Without inductance: (u_m − k_b θ̇_m) / R_m.
};

enum class DcMotorModel {
  /// State (θ_m, θ̇_m, i): L_m di/dt = u_m − R_m i − k_b θ̇_m (eqs. 2.1, 2.4a) and
  /// J_eff θ̈_m = k_m i − B_m θ̇_m − (r/η)(τ_g − τ_e) (eqs. 2.3, 2.4b, 3.8, 4.6).
  kWithInductance,
  /// State (θ_m, θ̇_m), t_e ≪ t_m (eq. 2.6):
  /// (k_m/R_m) u_m = J_eff θ̈_m + B θ̇_m + (r/η) τ_g − (r/η) τ_e (eqs. 3.9, 4.6).
  kWithoutInductance,
};

/// Integrates either model over one tick of length dt under a voltage u_m held constant over the
/// tick (zero-order hold) and an external wrench that may depend on the state (the operator's
/// hand), re-evaluated at every stage of the integrator.
///
/// Integrator: selectable (engine/core/integrator.hpp), default classical RK4, with n equal
/// sub-steps per tick. n is the configured count, raised for the model with inductance to
/// ceil(dt / (t_e / 2)) so that the electrical pole (≈ −1/t_e) sits at h λ ≈ −0.5, inside every
/// offered method's stability interval (Euler: (−2, 0]; RK4: (−2.78, 0]). Dropping the inductance
/// is therefore also what makes the simplified model cheap: its stiffest pole is the loaded
/// mechanical one, B / J_eff.
class DcMotorPlant {
 public:
  DcMotorPlant(const DcMotorParams& params, DcMotorModel model, const DcMotorState& initial = {},
               IntegrationSettings integration = {});

  /// external(theta_m, omega_m) -> ExternalWrench. Not allocating: a plain callable, inlined.
  template <typename ExternalWrenchFn>
  void step(double u_m, double dt, ExternalWrenchFn&& external) {
    IntegrationSettings tick = integration_;
    tick.substeps = substeps_for(dt);
    StateVector<3> x{state_.theta_m, state_.omega_m, state_.i};
    integrate_tick<1>(tick, x, dt, [&](const StateVector<3>& y) {
      const DcMotorState s{y[0], y[1], y[2]};
      const Derivative d = derivative(s, u_m, torque_at(s, external));
      return StateVector<3>{d.theta_m, d.omega_m, d.i};
    });
    state_ = {x[0], x[1], x[2]};
    if (model_ == DcMotorModel::kWithoutInductance) state_.i = algebraic_current(state_, u_m);
  }

  /// One tick with no external wrench.
  void step(double u_m, double dt);

  /// Sub-steps one tick of length dt takes (see the class comment).
  std::uint32_t substeps_for(double dt) const;

  const DcMotorState& state() const { return state_; }
  void set_state(const DcMotorState& state) { state_ = state; }
  const DcMotorParams& params() const { return params_; }
  DcMotorModel model() const { return model_; }
  const IntegrationSettings& integration() const { return integration_; }

 private:
  struct Derivative {
    double theta_m = 0.0;
    double omega_m = 0.0;
    double i = 0.0;
  };

  template <typename ExternalWrenchFn>
  double torque_at(const DcMotorState& s, ExternalWrenchFn& external) const {
    return external_joint_torque(params_, params_.r * s.theta_m, external(s.theta_m, s.omega_m));
  }
  /// Right-hand side of the chosen model; tau_e is the load-side external torque (eq. 4.3).
  Derivative derivative(const DcMotorState& s, double u_m, double tau_e) const;
  double algebraic_current(const DcMotorState& s, double u_m) const;

  DcMotorParams params_;
  DcMotorModel model_;
  DcMotorState state_;
  IntegrationSettings integration_;
  // Cached combinations, so a stage does no divisions it can avoid.
  double inv_J_eff_;
  double gear_;  // r / η
};

}  // namespace haptic::engine
