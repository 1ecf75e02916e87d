#pragma once
// Document 004 (Russo 1990, "The Design and Implementation of a Three Degree of Freedom Force
// Output Joystick"): a 3-DOF joystick, two gimbal rings (θ, Φ) and a shaft sliding through the
// gimbal centre (R), every axis driven by a DC motor and a magnetic-particle brake, all grounded.
//
// Frame W: origin at the gimbal centre, z along the shaft at θ = Φ = 0 (towards the handle); θ
// turns the shaft towards +x, Φ towards −y (eq. 3.1: tan θ = R_x/R_z, tan Φ = −R_y/R_z). The tool
// point T is the handle, at distance R from the centre along the shaft.
// Joint coordinates (the document's, §3.1.2): q = (θ, Φ, Ψ), Ψ the shaft-axis drive-pulley angle,
// R = r Ψ (eq. 3.12). Angles in rad, R in m, torques in N·m (the shaft axis' at the drive pulley).
//
// Sources: kinematics eqs. 3.1–3.22 (L538–L668), inertia eq. 3.27 (L727), cable transmission
// eqs. 3.28–3.44 (L752–L843), actuators §2.2.3 (L378, L381), contact model eq. 4.4 (L932).
// Lines are in ../shared/seeds/004_0284c21444d27e5c.txt.

#include <array>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <string>

#include "engine/core/integrator.hpp"
#include "engine/core/vec3.hpp"
#include "engine/device/joint_friction.hpp"

namespace haptic::engine {

/// Row-major 3×3 matrix for the joystick's maps: m[row][column].
using JoystickMatrix = std::array<std::array<double, 3>, 3>;

/// Axis indices of (θ, Φ, Ψ) in joint vectors.
enum JoystickAxis : std::size_t { kJoystickTheta = 0, kJoystickPhi = 1, kJoystickShaft = 2 };

/// Joint position (θ, Φ, R). Units: rad, rad, m.
struct JoystickPose {
  double theta = 0.0;
  double phi = 0.0;
  double R = 0.2;
};

// ---------------------------------------------------------------------------------------------
// Kinematics (§3.1). A = √(1 − sin²θ sin²Φ) throughout.

/// Handle position in W from (θ, Φ, R), eq. 3.3 (L556). Unit: m.
Vec3 joystick_forward(const JoystickPose& q);
/// (θ, Φ, R) from the handle position in W, eq. 3.1 (L538), with atan2 so that the quadrant is
/// right for p_z > 0 (the workspace). Units: rad, rad, m.
JoystickPose joystick_inverse(const Vec3& p_WT);
/// Unit vector along the shaft, n_s = x / R, eq. 3.4 (L562).
Vec3 joystick_shaft_direction(double theta, double phi);

/// ∂x/∂(θ, Φ, Ψ) at R = r Ψ, eq. 3.13 (L614) with two printed signs corrected (derived by
/// differentiating eq. 3.3; checked against central differences in the tests):
///   (2,3) printed +r sΦ cθ / A, correct −r sΦ cθ / A (R_y = −R sΦ cθ / A);
///   (3,1) printed +rΨ sθ cΦ³ / A³, correct −rΨ sθ cΦ³ / A³.
/// `r`: drive-pulley radius (m). Columns: m/rad.
JoystickMatrix joystick_jacobian(double theta, double phi, double psi, double r);
/// The same map with the shaft column in R: ∂x/∂(θ, Φ, R); its third column is n_s. Used for the
/// handle, where R is the load-side shaft position.
JoystickMatrix joystick_jacobian_R(double theta, double phi, double R);
/// det J = −r³ Ψ² cos θ cos Φ / A³, eq. 3.15 (L624). Unit: m³/rad².
double joystick_jacobian_determinant(double theta, double phi, double psi, double r);
/// J⁻¹, eq. 3.19 (L648) — as printed, it inverts the corrected J (zeros at (1,2) and (2,1)).
JoystickMatrix joystick_jacobian_inverse(double theta, double phi, double psi, double r);
/// Load-cell frame T (rows n_mx, n_my, n_mz), F_m = T F, eq. 3.10 (L590); a rotation.
JoystickMatrix joystick_load_cell_rotation(double theta, double phi);
/// τ = Jᵀ Tᵀ F_m, eq. 3.21 (L662), lower triangular:
///   [[rΨ cΦ / A², 0, 0], [−rΨ sθ sΦ cθ / A², −rΨ cθ / A, 0], [0, 0, r]]
/// (printed (2,1) is +; the product of the corrected J and eq. 3.10 gives −, and so does the
/// power balance τ·q̇ = F_m·(T v)). Eq. 3.22 inherits the printed sign.
JoystickMatrix joystick_measured_force_to_torque(double theta, double phi, double psi, double r);

/// m v.
Vec3 joystick_multiply(const JoystickMatrix& m, const Vec3& v);
/// mᵀ v (τ = Jᵀ F, eq. 3.18).
Vec3 joystick_multiply_transposed(const JoystickMatrix& m, const Vec3& v);

// ---------------------------------------------------------------------------------------------
// Parameters.

/// Physical parameters. From the document unless marked [I] (inferred or chosen here: the
/// document gives no masses or inertias, and its measured plots are lost).
struct GimbalJoystickParams {
  // Geometry.
  double r = 0.009525;  // Drive-pulley radius (code, L2297). Unit: m.
  double R_min = 0.1651;  // Shortest R, the shaft's offset past the centre (code L2357). Unit: m.
  /// Longest R [I]: R_min + 6 in, so that ±π/4 of gimbal travel at mid-stroke spans ≈ 1 ft³ (L64).
  double R_max = 0.3175;  // Unit: m.
  double gimbal_limit = std::numbers::pi / 4.0;  // Gimbal travel ±π/4 (L626). Unit: rad.

  // Inertia (eq. 3.27: diagonal). [I] constant values; the configuration dependence of H11, H22
  // (the shaft's inertia times cos²) is neglected.
  double I_theta = 2.5e-3;  // θ axis: ring, shaft, rotors. Unit: kg·m².
  double I_phi = 2.5e-3;    // Φ axis. Unit: kg·m².
  /// Shaft axis, motor side: motor and brake rotors reflected through r (L935's M_m) [I].
  double M_m = 0.30;  // Unit: kg.
  /// Shaft axis, load side: shaft and load cell, H33 / r² (eq. 3.27; L935's M_s) [I].
  double M_s = 0.11;  // Unit: kg.
  // M_m + M_s = 0.41 kg puts eq. 4.5's first breakpoint at the stated 41 rad/s (L940).

  // Cable-and-sleeve transmission (§3.2.2, L935).
  double k_t = 82340.0;  // Cable stiffness. Unit: N/m.
  double b_t = 45.0;     // Viscous damping across the cable. Unit: N·s/m.
  /// Sleeve Coulomb friction on the shaft (eq. 3.38's F_d) [I]: the code's feed-forward offsets
  /// +150 / −100 DAC counts (L2582–L2584) at 2319.1163 counts/N·m and r give 6.79 N and 4.53 N;
  /// their mean is the friction, their half-difference a gravity offset not modelled here.
  double F_d = 5.66;  // Unit: N.
  /// Coulomb friction in each gimbal axis [I]: the ≈ 1 N hysteresis at the endpoint
  /// (L1050, L1056) at the 20 cm lever arm (L1029).
  double gimbal_friction = 0.2;  // Unit: N·m.
  /// Narrowest band treated as zero velocity by the friction and brake models (the plant widens
  /// it to what the friction removes in one sub-step).
  double stick_velocity = 1e-4;  // Unit: rad/s (gimbal) and m/s (shaft).

  // Actuators (§2.2.3). Motors: printed-disk, mechanical time constant 8.8 ms (L378); brakes:
  // magnetic particle, 12 ms (L381). Limits from the DAC scalings [I]: motor ±2047 counts /
  // 1149.6285 (θ, Φ) and / 2319.1163 (shaft) counts/N·m; brake 3900 counts / 501.563 (θ, Φ) and
  // / 3399.209 (shaft) counts/N·m.
  double motor_time_constant = 8.8e-3;   // Unit: s.
  double brake_time_constant = 12e-3;    // Unit: s.
  double motor_limit_gimbal = 1.78;      // Unit: N·m.
  double motor_limit_shaft = 0.883;      // Unit: N·m.
  double brake_limit_gimbal = 7.78;      // Unit: N·m.
  double brake_limit_shaft = 1.15;       // Unit: N·m.
  /// Residual-magnetism torque the brakes keep at zero command (L381, L1041) [I]: 1 % of the limit.
  double brake_residual_gimbal = 0.0778;  // Unit: N·m.
  double brake_residual_shaft = 0.0115;   // Unit: N·m.

  /// Empty when usable; otherwise one message naming the first bad parameter
  /// ("M_s: must be finite and > 0, got -1").
  std::string validate() const;

  double motor_limit(std::size_t axis) const {
    return axis == kJoystickShaft ? motor_limit_shaft : motor_limit_gimbal;
  }
  double brake_limit(std::size_t axis) const {
    return axis == kJoystickShaft ? brake_limit_shaft : brake_limit_gimbal;
  }
  double brake_residual(std::size_t axis) const {
    return axis == kJoystickShaft ? brake_residual_shaft : brake_residual_gimbal;
  }
};

/// What the joystick's amplifiers are told, per axis (θ, Φ, Ψ). Motor torques are signed; brake
/// torques are the clamping torque of the Coulomb element, ≥ 0 (eq. 4.6's τ_b magnitude).
struct JoystickActuatorCommand {
  std::array<double, 3> motor{};  // Unit: N·m.
  std::array<double, 3> brake{};  // Unit: N·m, in [0, brake limit].

  /// Empty when usable: finite, brakes in [0, limit] — a brake torque above its declared limit
  /// is rejected here, not silently clamped ("brake[0]: must be in [0, 7.78], got 9").
  std::string validate(const GimbalJoystickParams& params) const;
};

// ---------------------------------------------------------------------------------------------
// The plant.

/// State layout for the integrator (positions, then their velocities, then first-order states):
/// [θ, Φ, x_m, R, θ̇, Φ̇, ẋ_m, Ṙ, τ_m(3), τ_b(3)]. x_m = r Ψ is the motor side of the cable (what
/// the shaft encoder measures, m); R the load side, the shaft itself (m); τ_m the motors' torques
/// (N·m); τ_b the brakes' clamping torques (N·m, ≥ 0).
namespace joystick_state {
inline constexpr std::size_t kPositions = 4;
inline constexpr std::size_t kSize = 14;
inline constexpr std::size_t kTheta = 0, kPhi = 1, kXm = 2, kR = 3;
inline constexpr std::size_t kThetaDot = 4, kPhiDot = 5, kXmDot = 6, kRDot = 7;
inline constexpr std::size_t kMotor = 8, kBrake = 11;
}  // namespace joystick_state

using JoystickState = StateVector<joystick_state::kSize>;

/// The three axes with the operator's hand on the handle:
///   θ, Φ:  I θ̈ = τ_m + τ_hand − friction(f_g + τ_b)                (eq. 3.27: diagonal inertia)
///   shaft: M_m ẍ_m = τ_m / r − f_t − brake(τ_b / r)                  (motor side of the cable)
///          M_s R̈   = f_t + F_hand·n_s − friction(F_d)                (load side, eq. 3.38's F_d)
///          f_t = k_t (x_m − R) + b_t (ẋ_m − Ṙ)                       (L935)
///   τ̇_m = (sat(u_m) − τ_m) / 8.8 ms,  τ̇_b = (u_b − τ_b) / 12 ms      (first-order lags, L378, L381)
/// A brake is a Coulomb element of capacity max(τ_b, residual) (L963); a joint friction and a
/// brake on the same coordinate add their capacities. Both use CoulombViscousFriction::resisting
/// (Karnopp) with a stick band of max(stick_velocity, capacity h / mass): the speed the friction
/// takes away in one sub-step h. Narrower, a fixed step jumps across zero velocity and the
/// Runge–Kutta stages, seeing the friction flip, add a spurious push (a limit cycle of ≈ 0.25 rad/s
/// on a braked gimbal axis at 10 kHz). After every sub-step a coordinate inside that band or across
/// zero velocity, whose applied torque the capacity holds, is set to rest (no creep).
/// The hand's mass adds m_h |∂x/∂q_i|² to each axis (the off-diagonal m_h JᵀJ terms are
/// neglected [I]); the hand force is re-evaluated at every integrator stage.
class GimbalJoystickPlant {
 public:
  GimbalJoystickPlant(const GimbalJoystickParams& params, const IntegrationSettings& settings,
                      const JoystickPose& initial);

  /// One tick of length dt (s) under `command` held over the tick. `hand(p_WT, v_WT) -> Vec3`:
  /// the hand's force on the handle in W (N). `hand_mass`: kg moving with the handle.
  template <typename HandFn>
  void step(const JoystickActuatorCommand& command, double dt, HandFn&& hand,
            double hand_mass = 0.0) {
    prepare(command, hand_mass);
    const std::uint32_t n = settings_.substeps > 0 ? settings_.substeps : 1;
    const double h = dt / static_cast<double>(n);
    h_ = h;
    for (std::uint32_t k = 0; k < n; ++k) {
      const std::array<double, 4> before{state_[4], state_[5], state_[6], state_[7]};
      integrate_step<joystick_state::kPositions>(
          settings_.method, state_, h, [&](const JoystickState& x) {
            Vec3 p_WT, v_WT;
            handle_state(x, p_WT, v_WT);
            return derivative(x, hand(p_WT, v_WT));
          });
      Vec3 p_WT, v_WT;
      handle_state(state_, p_WT, v_WT);
      settle(before, hand(p_WT, v_WT));
    }
  }
  /// One tick with nobody holding the handle.
  void step(const JoystickActuatorCommand& command, double dt);

  /// Handle (load side) position and velocity in W for a state. Units: m, m/s.
  void handle_state(const JoystickState& x, Vec3& p_WT, Vec3& v_WT) const;
  /// What the sensors see: encoders on the drive shafts (θ, Φ, Ψ = x_m / r) and tachometers.
  /// Units: rad, rad, rad; rad/s.
  Vec3 measured_joints() const;
  Vec3 measured_joint_rates() const;

  const JoystickState& state() const { return state_; }
  void set_state(const JoystickState& state) { state_ = state; }
  const GimbalJoystickParams& params() const { return params_; }
  const IntegrationSettings& settings() const { return settings_; }

  /// dx/dt for a state, the held command and a hand force (N, in W). Public for tests.
  JoystickState derivative(const JoystickState& x, const Vec3& F_hand_W) const;

 private:
  void prepare(const JoystickActuatorCommand& command, double hand_mass);
  /// Karnopp's stick: zero the velocity of a coordinate that ended the sub-step in the band or
  /// across zero (`before`: velocities at its start) when the capacity holds its load.
  void settle(const std::array<double, 4>& before, const Vec3& F_hand_W);
  /// The generalized forces other than friction and brakes on (θ, Φ, x_m, R). Units: N·m, N.
  std::array<double, 4> applied(const JoystickState& x, const Vec3& F_hand_W) const;
  std::array<double, 4> capacities(const JoystickState& x) const;
  /// The stick band for a coordinate of capacity `capacity` (see the class comment).
  double stick_band(double capacity, std::size_t i) const;

  GimbalJoystickParams params_;
  IntegrationSettings settings_;
  JoystickState state_{};
  // Held over the tick.
  std::array<double, 3> motor_command_{};  // saturated. Unit: N·m.
  std::array<double, 3> brake_command_{};  // Unit: N·m.
  std::array<double, 4> mass_{};           // I_θ, I_Φ (kg·m²), M_m, M_s (kg), with the hand.
  double h_ = 0.0;                         // The sub-step. Unit: s.
};

// ---------------------------------------------------------------------------------------------
// The cable drive and the sleeve (§3.2.2, L742–L800). r: drive-pulley radius (m); preload: the
// cable's pre-load tension T_PL (N); τ: drive torque (N·m).

/// The capstan's slip limit (eq. 3.29): the cable holds on the pulley while
/// (T_PL − τ/2r) / (T_PL + τ/2r) >= e^{−μβ}, i.e. up to τ_max = 2 r T_PL tanh(μβ/2).
/// mu_beta: friction coefficient × wrap angle (rad). Unit: N·m.
double capstan_slip_torque(double r, double preload, double mu_beta);

/// The force along the shaft after the sleeve (eqs. 3.30–3.32): the cable's two sides leave the
/// pulley at T_PL ∓ τ/2r and the sleeve's bend α (friction ν) scales them by e^{±να}, so
/// F_R = (τ/r) cosh(να) − 2 T_PL sinh(να): a load factor 2 cosh(να) on τ/2r (eq. 3.33) and a
/// friction 2 T_PL sinh(να) (eq. 3.37 prints it with the opposite sign). Unit: N.
double sleeve_shaft_force(double tau, double r, double preload, double nu_alpha);

/// The torque at which the shaft breaks away, F_R = 0 (eq. 3.34): τ_c = 2 r T_PL tanh(να), fed
/// forward by the force loop (L872). Unit: N·m.
double sleeve_breakaway_torque(double r, double preload, double nu_alpha);

// ---------------------------------------------------------------------------------------------
// Eq. 3.38, cleaned: the 1-DOF shaft model with the motor side held.

/// Parameters of m_s r² Ψ̈ + F_d r sgn(Ψ̇) + k r² Ψ = τ cosh(να) (eq. 3.38 with the right-hand side
/// multiplied by r: as printed, τ/(2r)(e^{−να} + e^{να}) is a force on a torque balance; F_d is the
/// magnitude 2 T_PL sinh(να) — eq. 3.37 prints T_PL(e^{−να} − e^{να}), which is negative).
struct CableTransmissionParams {
  double m_s = 0.11;      // Shaft mass [I]. Unit: kg.
  double k = 82340.0;     // Cable stiffness (L935). Unit: N/m.
  double F_d = 5.66;      // Sleeve Coulomb friction [I]. Unit: N.
  double r = 0.009525;    // Drive-pulley radius. Unit: m.
  double nu_alpha = 0.0;  // Sleeve friction × bend, ν α (eq. 3.30). Unit: rad.
  double stick_velocity = 1e-4;  // Unit: rad/s.

  std::string validate() const;
  /// Natural frequency ω_n = √(k / m_s) (eq. 3.40). Unit: rad/s.
  double natural_frequency() const;
  /// The friction band F_d / (k r): the amplitude drops by twice this per half cycle
  /// (eq. 3.42), and motion stops inside ±this (eq. 3.44 as corrected). Unit: rad.
  double friction_band() const { return F_d / (k * r); }
};

/// State (Ψ, Ψ̇). Units: rad, rad/s.
class CableTransmissionModel {
 public:
  CableTransmissionModel(const CableTransmissionParams& params, const IntegrationSettings& settings,
                         double psi0, double psi_dot0 = 0.0);
  /// One tick of dt (s) under the drive torque τ (N·m).
  void step(double tau, double dt);
  double psi() const { return x_[0]; }
  double psi_dot() const { return x_[1]; }

 private:
  CableTransmissionParams params_;
  IntegrationSettings settings_;
  StateVector<2> x_{};
  double inertia_;  // m_s r². Unit: kg·m².
};

}  // namespace haptic::engine
