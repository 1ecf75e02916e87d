#pragma once
// Document 003's haptic device: Madill 1998's gravity-balanced, dynamically decoupled five-bar
// linkage (Madill, "Modelling and Control of a Haptic Interface: A Mechatronics Approach", ch. 3.13,
// 4.2, 5), with its last link rigid or, optionally, carrying one flexible mode
// (FiveBarFlexibleMode).
//
// Joints (Table 3.1, L2090–2101): q0 the base ("horizontal", about the vertical axis z0), q1 the
// axial joint (link 1), q2 the vertical joint (link 2 of the parallelogram). Home pose
// q = (0, 90°, 180°) (L2726). Frames: W is the thesis' base frame x0–y0–z0 (L2049) with z0
// vertical (gravity along −z0); the origin is the fulcrum, the centre of joints 1–2 (L2258).
// T is the rigid tool tip at l_f = l4 + l5 from joint 1's far end, on the line of link 4/5.
// Angles in rad, angular velocities in rad/s, torques in N·m, lengths in m.

#include <array>
#include <cmath>
#include <cstdint>
#include <string>

#include "engine/core/integrator.hpp"
#include "engine/core/vec3.hpp"
#include "engine/device/flexible_link.hpp"
#include "engine/device/joint_friction.hpp"

namespace haptic::engine {

/// One value per joint, in the order (q0 horizontal/base, q1 axial, q2 vertical).
using FiveBarJoints = std::array<double, 3>;
/// A 3×3 matrix, row-major: m[row][column].
using FiveBarMatrix = std::array<std::array<double, 3>, 3>;

/// The home pose q = (0, 90°, 180°) (L2726, "q1 = 90° and q2 = 180°"). Unit: rad.
FiveBarJoints five_bar_home();

/// Parameters of the rigid plant.
///
/// Inertias. Eq. 4.10 with α3 = 0 gives D = diag(α1 C1² + α2 C2², α1, α2) for links treated as
/// lines; the base joint also carries the hub (motor, joint, base structure), J_h, constant. The
/// defaults are the identified inertias of Table 5.4 (L2617–2621): α1 = J(axial) = 0.204,
/// α2 = J(vertical) = 0.026, and J_h = J(horizontal at home) − α2 = 0.733 − 0.026 = 0.707
/// (at home C1 = 0, C2 = −1, so D00 = J_h + α2) [inference: the thesis gives no split of D00].
/// Why the identified set: it is the one measured together with the friction B and f below (one
/// P(s) = 1/(Js² + Bs) fit per joint, eq. 5.7), and the one the thesis' estimator uses
/// (eq. 6.5, P = 1/(0.204 s² + 0.012 s)); it includes the motor rotors, which the line-link
/// theory omits. theoretical() gives Table 5.5's set (0.199, 0.032, 0.708 at home) with the hub
/// inertia J0 = 0.677 of §5.4.2 (L2806): 0.677 + 0.032 = 0.709 ≈ 0.708, which is how the
/// theoretical set splits.
///
/// Friction: Table 5.4's viscous B and Coulomb f per joint (the axial hand-tuned 0.061 N·m of
/// L2690 is the estimator's value, not the plant's). Encoders: Table 5.2 (L2467) with the axial
/// scale corrected to −π/6000 as chapter 6 uses it (L3150, L3222; 157 µm at 0.30 m). Torque
/// limits: the D/A chain K_m K_a V_a of L3237 with each axis' Table 5.1 transconductance.
struct FiveBarParams {
  double l1 = 0.30;   // Link 1 (and 3). Eq. 5.4. Unit: m.
  double l_f = 0.60;  // Joint 1's far end to the tool tip, l4 + l5. Eq. 5.5. Unit: m.

  double alpha1 = 0.204;  // α1, eq. 4.7; Table 5.4 axial J. Unit: kg·m².
  double alpha2 = 0.026;  // α2, eq. 4.8; Table 5.4 vertical J. Unit: kg·m².
  /// α3, eq. 4.9: the coupling inertia m3 lc3 l2 − mr lcr l1; 0 when the link-3 counterbalance
  /// decouples the robot (eq. 4.6). Unit: kg·m².
  double alpha3 = 0.0;
  double J_hub = 0.707;  // Base-joint hub inertia (see above). Unit: kg·m².

  /// Per joint (q0, q1, q2): Table 5.4's f (N·m) and B (N·m·s/rad). The stick band v_s = 1e-3
  /// rad/s is a simulation choice: wide enough that Coulomb deceleration f h / J cannot jump
  /// across it in one 100 µs sub-step (≤ 3.2e-4 rad/s, vertical joint), and 1/500 of the velocity
  /// an encoder count per 1 ms period resolves (0.52 rad/s).
  std::array<CoulombViscousFriction, 3> friction{{
      {0.125, 0.045, 1e-3},  // horizontal q0 (z_e)
      {0.088, 0.012, 1e-3},  // axial q1 (x_e)
      {0.082, 0.009, 1e-3},  // vertical q2 (y_e)
  }};

  /// Encoder scale K_e per joint, signed as the thesis gives it (a negative scale counts the
  /// other way). Table 5.2 with ch. 6's axial correction. Unit: rad/count.
  FiveBarJoints encoder_rad_per_count{3.14159265358979323846 / 6000.0,
                                      -3.14159265358979323846 / 6000.0,
                                      3.14159265358979323846 / 4000.0};

  /// Peak joint torque the D/A chain can command, τ_d = K_m K_a V_a (L3237): K_m = 0.373 N·m/A,
  /// K_a = 3.98 / 3.87 / 3.96 A/V (Table 5.1, base / axial / vertical), V_a = 5 V. The axial
  /// value is 7.218 N·m (printed 7.23). Unit: N·m.
  FiveBarJoints torque_limit{0.373 * 3.98 * 5.0, 0.373 * 3.87 * 5.0, 0.373 * 3.96 * 5.0};

  /// Empty when usable, otherwise one message naming the first bad parameter
  /// ("alpha1: must be finite and > 0, got -1").
  std::string validate() const;

  /// The defaults (Table 5.4 identified inertias, see above).
  static FiveBarParams identified() { return {}; }
  /// Table 5.5's theoretical inertias with the §5.4.2 hub inertia.
  static FiveBarParams theoretical();
};

// ---------------------------------------------------------------------------------------------
// Kinematics (rigid link 5).

/// Tool tip position p_WT(q) = [(l1 C1 − l_f C2) C0, (l1 C1 − l_f C2) S0, l1 S1 − l_f S2]: the
/// translation of eq. 3.118 with l4 replaced by l_f (the tip rather than link 5's clamp). Unit: m.
Vec3 five_bar_tip_position(const FiveBarParams& params, const FiveBarJoints& q);

/// Linear-velocity Jacobian of the tip, v_WT = J(q) q̇: eq. 3.120 with l4 → l_f. Unit: m/rad.
FiveBarMatrix five_bar_jacobian(const FiveBarParams& params, const FiveBarJoints& q);

/// Joint torques for a force on the tip, τ = Jᵀ F (eq. 3.58). Units: N in, N·m out.
FiveBarJoints five_bar_joint_torque(const FiveBarParams& params, const FiveBarJoints& q,
                                    const Vec3& F_T_W);

/// Which of the two arm configurations inverse kinematics returns. γ is the angle of link 4/5
/// relative to link 1's line, γ = q2 − q1 − π (so q2 − q1 = γ + π).
enum class FiveBarBranch : std::uint8_t {
  kElbowDown,  // γ ∈ [−π, 0]: q2 − q1 ∈ [0, π], the device's own (home: γ = −90°).
  kElbowUp,    // γ ∈ [0, π]: the mirror image, outside the parallelogram's range.
};

/// Inverse kinematics [inference: not in the thesis, derived from five_bar_tip_position]:
/// q0 = atan2(y, x); ρ = √(x² + y²) (taken ≥ 0); D² = ρ² + z²;
/// cos γ = (D² − l1² − l_f²) / (2 l1 l_f); q1 = atan2(z, ρ) − atan2(l_f sin γ, l1 + l_f cos γ);
/// q2 = q1 + γ + π. Returns false (q untouched) when the point is out of reach
/// (|cos γ| > 1) or on the base axis (ρ = 0, where q0 is undefined).
bool five_bar_inverse_kinematics(const FiveBarParams& params, const Vec3& p_WT,
                                 FiveBarBranch branch, FiveBarJoints& q);

// ---------------------------------------------------------------------------------------------
// Dynamics.

struct FiveBarState {
  FiveBarJoints q = five_bar_home();  // Unit: rad.
  FiveBarJoints qdot{};               // Unit: rad/s.
};

/// The state of link 5's flexible mode: η is q_1 of eqs. 3.29–3.31 (the thesis' ν in the
/// five-bar's L2032), the coordinate of the normalized clamped-free shape φ1 (∫₀ˡ φ1² dx = 1), so
/// the tip deflects by φ1(l) η. Positive η bends the tip the way positive q̇0 moves it.
struct FiveBarModeState {
  double eta = 0.0;      // η. Unit: m^(3/2) (φ1 carries m^(−1/2), φ1 η is in m).
  double eta_dot = 0.0;  // η̇. Unit: m^(3/2)/s.
};

/// One flexible mode of link 5, bending in the horizontal plane and coupled to the base joint q0,
/// as in the single flexible link of eqs. 3.29–3.31 (Madill, §3.3) with n = 1:
///   (D00(q1, q2) + ρ η²) q̈0 + ρ β1 η̈ + c0 + 2 ρ η η̇ q̇0 = τ0 − τ_f0 + (Jᵀ F)0,
///   ρ η̈ + ρ β1 q̈0 − ρ η q̇0² + 2 ζ ω1 ρ η̇ + ρ ω1² η = φ1(l) n·F,
/// where n = (−S0, C0, 0) is the horizontal direction perpendicular to the link (−z_e of
/// eq. 3.118) and F the force on the tip. Why the horizontal direction and q0: it is the only one
/// the hub couples to (L2032, footnote 4: the vertical modes do not interact with q0), and the
/// lowest structural mode the thesis measured is horizontal (≈ 19 Hz, L2726, L2830). The link's
/// rigid rotary inertia ⅓ρl³ of eq. 3.29 is not added: the identified D00 (Table 5.4) holds it.
/// The coupling ρβ1 is the single link's, clamp on the axis [simplification: on the five-bar the
/// clamp sits ≈ 0.15 m out and the link tilts with q2, which would scale the coupling; L2117].
///
/// Defaults: the thesis' beam (HubPayloadBeamParams: L = 0.449 m, ρ = 0.163 kg/m) with ω1 the
/// hub + payload frequency of eq. 5.11, 222.31 rad/s (printed 223). In eq. 3.30 ω1 is the mode's
/// frequency with the hub held; with the hub free the coupled mode rises by 1/√(1 − ρβ1²/D00),
/// to 223.04 rad/s at home (D00 = 0.733 kg·m²): 0.12 Hz, the small hub effect L2832 reports.
/// The payload's mass is carried by ω1 alone, not by the modal mass, so the tip's static
/// compliance φ1(l)²/(ρω1²) = 1.11 mm/N is ≈ 3× the bare tube's l³/(3EI) = 0.34 mm/N: the
/// frequency is the thesis', the stiffness softer [consequence of the single-link model].
/// ζ = 0.02: the thesis measures no damping for link 5; the aluminium alone would give far less
/// (a material loss factor of ≈ 1e−3, ζ ≈ 5e−4), but the clamp at link 4 and the bolted load
/// cell add joint damping, and 1–5 % is the usual range for bolted light-alloy structures
/// [assumption].
struct FiveBarFlexibleMode {
  double omega = 222.30927722583857;  // ω1, with the hub held (eq. 3.30). Unit: rad/s.
  double zeta = 0.02;                 // ζ, modal damping ratio (see above). Dimensionless.
  double rho = 0.163;                 // ρ, the link's mass per length (modal mass). Unit: kg/m.
  /// β1 = ∫₀ˡ x φ1 dx = 2 l^(3/2) / (p1 l)² (clamped_free_participation). Unit: m^(3/2).
  double beta = 0.17113890732627945;
  /// φ1(l) = 2 / √l, the shape at the tip (clamped_free_tip_value). Unit: m^(−1/2).
  double tip_shape = 2.9847421946994452;

  /// The mode of a beam `beam` (ω1 from eq. 5.11, β1 and φ1(l) from the clamped-free shape of
  /// length beam.L, ρ = beam.rho) with damping ratio zeta. The defaults are
  /// from_beam(HubPayloadBeamParams{}, 0.02).
  static FiveBarFlexibleMode from_beam(const HubPayloadBeamParams& beam, double zeta);

  /// Empty when usable, otherwise one message naming the first bad parameter.
  std::string validate() const;
};

/// Options the plant is built with.
struct FiveBarPlantOptions {
  /// RK4 with 10 sub-steps (h = 100 µs at 1 kHz): the fastest pole the plant sees is the tight
  /// grip's hand spring on the vertical joint (800 N/m × 0.6² m² / 0.026 kg·m²:
  /// ω ≈ 105 rad/s, with its damping ≈ 208 1/s), so |hλ| ≤ 0.03, where RK4's local error is
  /// negligible, and a joint decelerating under Coulomb friction lands in the stick band.
  IntegrationSettings integration{Integrator::kRk4, 10};
  /// Keep the centripetal/Coriolis terms of L2382. Dropping them is the thesis' "haptic speeds"
  /// approximation (L2388: velocities are small, the robot behaves as SISO double integrators).
  bool coriolis = true;
  /// Add link 5's first horizontal mode (FiveBarFlexibleMode; off by default). With it the
  /// integrated state is [q0, q1, q2, η, q̇0, q̇1, q̇2, η̇]; without it the plant is the rigid one,
  /// step for step the same arithmetic. `coriolis = false` also drops the mode's velocity terms.
  bool flexible_mode = false;
  FiveBarFlexibleMode mode;
};

/// Joint and modal accelerations of the flexible plant. Units: rad/s², m^(3/2)/s².
struct FiveBarFlexibleAcceleration {
  FiveBarJoints qddot{};
  double eta_ddot = 0.0;
};

/// A symmetric 4×4 matrix over (q0, q1, q2, η), row-major.
using FiveBarFlexibleMatrix = std::array<std::array<double, 4>, 4>;

/// The rigid, gravity-balanced five-bar (L2382 for α3 = 0; the general α3 terms follow from
/// eq. 4.10 by Lagrange's equations [derived here], and reduce to L2382 at α3 = 0):
///   D(q) q̈ + c(q, q̇) = sat(τ) − τ_f(q̇) + Jᵀ F_hand,
///   D00 = J_h + α1 C1² + α2 C2² + 2 α3 C1 C2, D11 = α1, D22 = α2, D12 = α3 C(2−1);
///   c0 = (∂D00/∂q1 q̇1 + ∂D00/∂q2 q̇2) q̇0 = −2(α1 C1 S1 q̇1 + α2 C2 S2 q̇2) q̇0 at α3 = 0,
///   c1 = −½ ∂D00/∂q1 q̇0² − α3 S(2−1) q̇2², c2 = −½ ∂D00/∂q2 q̇0² + α3 S(2−1) q̇1².
/// No gravity term: the counterbalances zero the potential energy (L2371–2380). A point mass m at
/// the tip (the operator's hand) adds m JᵀJ to D and m Jᵀ J̇ q̇ to c. τ_f is Table 5.4's
/// Coulomb + viscous friction through CoulombViscousFriction::resisting (Karnopp stick; exact on
/// the decoupled joints, approximate when α3 or the hand mass couple q1 and q2), and after each
/// sub-step a joint inside the stick band that friction can hold is set at rest. The commanded
/// torque is held over the tick (zero-order hold) and saturated at torque_limit.
///
/// With options.flexible_mode the mode of FiveBarFlexibleMode joins as a fourth coordinate η: the
/// tip becomes p_WT = p_rigid(q) + φ1(l) η n(q0), the mass matrix the 4×4 of eq. 3.31 over
/// (q, η) (plus m J_fᵀJ_f for a tip mass, J_f = ∂p_WT/∂(q, η)), and friction acts on the joints
/// with η eliminated (the Schur complement), so a stuck hub holds against the ringing link.
class FiveBarPlant {
 public:
  explicit FiveBarPlant(const FiveBarParams& params, const FiveBarState& initial = {},
                        const FiveBarPlantOptions& options = {});

  /// Advances one tick of length dt (s). `tip_force(p_WT, v_WT) -> Vec3` is the force on the tip
  /// in W (N), re-evaluated at every stage; `tip_mass` a mass moving with the tip (kg).
  template <typename TipForceFn>
  void step(const FiveBarJoints& tau_command, double dt, TipForceFn&& tip_force,
            double tip_mass = 0.0) {
    for (std::size_t i = 0; i < 3; ++i) {
      applied_[i] = saturate(tau_command[i], params_.torque_limit[i]);
    }
    if (options_.flexible_mode) {
      step_flexible(dt, tip_force, tip_mass);
      return;
    }
    StateVector<6> x{state_.q[0],    state_.q[1],    state_.q[2],
                     state_.qdot[0], state_.qdot[1], state_.qdot[2]};
    const auto unpack = [](const StateVector<6>& s) {
      return FiveBarState{{s[0], s[1], s[2]}, {s[3], s[4], s[5]}};
    };
    const auto rhs = [&](const StateVector<6>& s) {
      const FiveBarState at = unpack(s);
      Vec3 p_WT, v_WT;
      tip_state(at, p_WT, v_WT);
      const FiveBarJoints a = acceleration(at, applied_, tip_force(p_WT, v_WT), tip_mass);
      return StateVector<6>{s[3], s[4], s[5], a[0], a[1], a[2]};
    };
    const std::uint32_t n = options_.integration.substeps > 0 ? options_.integration.substeps : 1;
    const double h = dt / static_cast<double>(n);
    for (std::uint32_t k = 0; k < n; ++k) {
      integrate_step<3>(options_.integration.method, x, h, rhs);
      // Karnopp's stick: a joint inside the stick band whose other torques friction can hold
      // is at rest (otherwise it would creep at up to v_s, decaying only through B).
      const FiveBarState at = unpack(x);
      Vec3 p_WT, v_WT;
      tip_state(at, p_WT, v_WT);
      const FiveBarJoints other = non_friction_torque(at, applied_, tip_force(p_WT, v_WT), tip_mass);
      for (std::size_t i = 0; i < 3; ++i) {
        const CoulombViscousFriction& f = params_.friction[i];
        if (std::abs(x[3 + i]) < f.stick_velocity && std::abs(other[i]) <= f.coulomb) {
          x[3 + i] = 0.0;
        }
      }
    }
    state_ = unpack(x);
  }

  /// One tick with nothing on the tip.
  void step(const FiveBarJoints& tau_command, double dt);

  /// Joint accelerations for torques `tau` (already saturated), a tip force F_T_W (N) and a tip
  /// mass (kg). Unit: rad/s².
  FiveBarJoints acceleration(const FiveBarState& s, const FiveBarJoints& tau, const Vec3& F_T_W,
                             double tip_mass = 0.0) const;

  /// Every torque on the joints but friction and inertia: sat(τ) − c(q, q̇) + Jᵀ F. Unit: N·m.
  FiveBarJoints non_friction_torque(const FiveBarState& s, const FiveBarJoints& tau,
                                    const Vec3& F_T_W, double tip_mass = 0.0) const;

  /// D(q) of eq. 4.10 (with the hub inertia) plus tip_mass · JᵀJ. Unit: kg·m².
  FiveBarMatrix mass_matrix(const FiveBarJoints& q, double tip_mass = 0.0) const;

  /// Velocity-product torques c(q, q̇) (see the class comment). Unit: N·m.
  FiveBarJoints velocity_torques(const FiveBarState& s, double tip_mass = 0.0) const;

  /// ½ q̇ᵀ D(q) q̇ with the tip mass. Unit: J.
  double kinetic_energy(const FiveBarState& s, double tip_mass = 0.0) const;

  /// Tip position (m) and velocity (m/s) in W.
  void tip_state(const FiveBarState& s, Vec3& p_WT, Vec3& v_WT) const;

  // -- The flexible mode (used when options().flexible_mode; callable either way). --

  /// The physical tip with the link's deflection: p_WT = p_rigid(q) + φ1(l) η n(q0),
  /// n = (−S0, C0, 0), and v_WT = J_f [q̇; η̇]. Units: m, m/s.
  void flexible_tip_state(const FiveBarState& s, const FiveBarModeState& m, Vec3& p_WT,
                          Vec3& v_WT) const;

  /// The tip as it is now: flexible_tip_state when the mode is on, tip_state otherwise.
  void physical_tip_state(Vec3& p_WT, Vec3& v_WT) const;

  /// M(q, η) of eq. 3.31 for the five-bar: D(q) with ρη² added to D00, ρβ1 coupling q0 and η,
  /// ρ on η, plus tip_mass · J_fᵀJ_f. Unit: kg·m² (joint–joint), kg·m^(1/2) (joint–η), kg/m (η–η).
  FiveBarFlexibleMatrix flexible_mass_matrix(const FiveBarJoints& q, double eta,
                                             double tip_mass = 0.0) const;

  /// Accelerations of the flexible plant for saturated torques `tau` (N·m), a tip force (N) at the
  /// deflected tip and a tip mass (kg).
  FiveBarFlexibleAcceleration flexible_acceleration(const FiveBarState& s,
                                                    const FiveBarModeState& m,
                                                    const FiveBarJoints& tau, const Vec3& F_T_W,
                                                    double tip_mass = 0.0) const;

  /// The joint torques friction must hold for q̈ = 0 with the mode free: every torque but
  /// friction and inertia after η is eliminated, Q_q − c_q − M_qη (Q_η − c_η) / M_ηη. Unit: N·m.
  FiveBarJoints flexible_non_friction_torque(const FiveBarState& s, const FiveBarModeState& m,
                                             const FiveBarJoints& tau, const Vec3& F_T_W,
                                             double tip_mass = 0.0) const;

  /// Kinetic energy ½ ẋᵀ M ẋ (links, mode, coupling, tip mass) plus the strain energy
  /// ½ ρ ω1² η². Unit: J.
  double flexible_energy(const FiveBarState& s, const FiveBarModeState& m,
                         double tip_mass = 0.0) const;

  const FiveBarState& state() const { return state_; }
  void set_state(const FiveBarState& state) { state_ = state; }
  /// The flexible mode's state (at rest, and unused, when the mode is off).
  const FiveBarModeState& mode_state() const { return mode_; }
  void set_mode_state(const FiveBarModeState& mode) { mode_ = mode; }
  /// The saturated torque applied over the last tick (what an estimator should be fed, L3230).
  const FiveBarJoints& applied_torque() const { return applied_; }
  const FiveBarParams& params() const { return params_; }
  const FiveBarPlantOptions& options() const { return options_; }

 private:
  /// The flexible plant's equations with η eliminated (see flexible_non_friction_torque).
  struct FlexibleSystem {
    FiveBarMatrix D{};        // M_qq − M_qη M_qηᵀ / M_ηη. Unit: kg·m².
    FiveBarJoints net{};      // Q_q − c_q − M_qη (Q_η − c_η) / M_ηη. Unit: N·m.
    FiveBarJoints m_qeta{};   // M_qη. Unit: kg·m^(1/2).
    double m_etaeta = 0.0;    // M_ηη. Unit: kg/m.
    double net_eta = 0.0;     // Q_η − c_η. Unit: kg·m^(1/2)/s².
  };
  FlexibleSystem flexible_system(const FiveBarState& s, const FiveBarModeState& m,
                                 const FiveBarJoints& tau, const Vec3& F_T_W,
                                 double tip_mass) const;

  /// One tick of the flexible plant (applied_ already saturated): state
  /// [q0, q1, q2, η, q̇0, q̇1, q̇2, η̇], the same integrator, sub-steps and stick rule as the rigid
  /// step, with friction on the η-eliminated joint torques.
  template <typename TipForceFn>
  void step_flexible(double dt, TipForceFn& tip_force, double tip_mass) {
    StateVector<8> x{state_.q[0],    state_.q[1],    state_.q[2],    mode_.eta,
                     state_.qdot[0], state_.qdot[1], state_.qdot[2], mode_.eta_dot};
    const auto joints = [](const StateVector<8>& s) {
      return FiveBarState{{s[0], s[1], s[2]}, {s[4], s[5], s[6]}};
    };
    const auto mode = [](const StateVector<8>& s) { return FiveBarModeState{s[3], s[7]}; };
    const auto rhs = [&](const StateVector<8>& s) {
      const FiveBarState at = joints(s);
      const FiveBarModeState m = mode(s);
      Vec3 p_WT, v_WT;
      flexible_tip_state(at, m, p_WT, v_WT);
      const FiveBarFlexibleAcceleration a =
          flexible_acceleration(at, m, applied_, tip_force(p_WT, v_WT), tip_mass);
      return StateVector<8>{s[4], s[5], s[6], s[7], a.qddot[0], a.qddot[1], a.qddot[2], a.eta_ddot};
    };
    const std::uint32_t n = options_.integration.substeps > 0 ? options_.integration.substeps : 1;
    const double h = dt / static_cast<double>(n);
    for (std::uint32_t k = 0; k < n; ++k) {
      integrate_step<4>(options_.integration.method, x, h, rhs);
      // Karnopp's stick as in step(), on the torques left once the mode is eliminated: a stuck
      // hub holds while the link rings against it.
      const FiveBarState at = joints(x);
      const FiveBarModeState m = mode(x);
      Vec3 p_WT, v_WT;
      flexible_tip_state(at, m, p_WT, v_WT);
      const FiveBarJoints other =
          flexible_non_friction_torque(at, m, applied_, tip_force(p_WT, v_WT), tip_mass);
      for (std::size_t i = 0; i < 3; ++i) {
        const CoulombViscousFriction& f = params_.friction[i];
        if (std::abs(x[4 + i]) < f.stick_velocity && std::abs(other[i]) <= f.coulomb) {
          x[4 + i] = 0.0;
        }
      }
    }
    state_ = joints(x);
    mode_ = mode(x);
  }

  FiveBarParams params_;
  FiveBarPlantOptions options_;
  FiveBarState state_;
  FiveBarModeState mode_{};
  FiveBarJoints applied_{};
};

// ---------------------------------------------------------------------------------------------
// Sensing.

/// What the encoders report: q_home + K_e floor((q − q_home) / K_e) per joint, the counts taken
/// from the home pose (the robot is started there [inference]) and K_e signed as in Table 5.2, so
/// a negative scale rounds the other way. Unit: rad.
FiveBarJoints five_bar_encoder_reading(const FiveBarParams& params, const FiveBarJoints& q);

/// The conventional velocity estimate (L2877–2881, eq. 6.2): a backward (Euler) difference of the
/// measured position, (q_k − q_{k−1}) / T, through a first-order low-pass ω0 / (s + ω0),
/// discretized exactly for a held input: v_k = a v_{k−1} + (1 − a) (q_k − q_{k−1}) / T,
/// a = exp(−ω0 T). The default ω0 = 20 rad/s is the cutoff of Fig. 6.16 (L3193).
struct BackwardDifferenceVelocity {
  double cutoff = 20.0;  // ω0 > 0. Unit: rad/s.
  FiveBarJoints previous{};  // q_{k−1}. Unit: rad.
  FiveBarJoints velocity{};  // v_{k−1}. Unit: rad/s.

  /// Starts at rest at q.
  void reset(const FiveBarJoints& q) {
    previous = q;
    velocity = {};
  }
  /// One sample q_k taken T = dt (s) after the previous one; returns v_k.
  const FiveBarJoints& update(const FiveBarJoints& q, double dt);
};

}  // namespace haptic::engine
