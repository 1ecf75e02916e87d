#include "engine/device/five_bar.hpp"
#include "engine/core/parameter_checks.hpp"

#include <cassert>
#include <cmath>
#include <numbers>
#include <sstream>

namespace haptic::engine {
namespace {

bool positive(double v) { return std::isfinite(v) && v > 0.0; }
bool non_negative(double v) { return std::isfinite(v) && v >= 0.0; }

constexpr const char* kJointSuffix[3] = {"[0]", "[1]", "[2]"};

/// The velocity-product part of the tip acceleration, J̇(q, q̇) q̇ (p̈ = J q̈ + J̇ q̇), from
/// differentiating five_bar_tip_position twice. Unit: m/s².
Vec3 tip_bias_acceleration(const FiveBarParams& p, const FiveBarState& s) {
  const double C0 = std::cos(s.q[0]), S0 = std::sin(s.q[0]);
  const double C1 = std::cos(s.q[1]), S1 = std::sin(s.q[1]);
  const double C2 = std::cos(s.q[2]), S2 = std::sin(s.q[2]);
  const double w0 = s.qdot[0], w1 = s.qdot[1], w2 = s.qdot[2];
  const double rho = p.l1 * C1 - p.l_f * C2;  // horizontal distance of the tip from the z0 axis
  const double rho_dot = -p.l1 * S1 * w1 + p.l_f * S2 * w2;
  const double rho_bias = -p.l1 * C1 * w1 * w1 + p.l_f * C2 * w2 * w2;
  const double z_bias = -p.l1 * S1 * w1 * w1 + p.l_f * S2 * w2 * w2;
  return {rho_bias * C0 - 2.0 * rho_dot * S0 * w0 - rho * C0 * w0 * w0,
          rho_bias * S0 + 2.0 * rho_dot * C0 * w0 - rho * S0 * w0 * w0, z_bias};
}

/// n(q0) = (−S0, C0, 0): horizontal, perpendicular to link 5, the way the tip moves for q̇0 > 0
/// (the deflection direction of the single link, L1950–1956).
Vec3 deflection_direction(double q0) { return {-std::sin(q0), std::cos(q0), 0.0}; }

/// Columns of J_f = ∂p_WT/∂(q0, q1, q2, η) for p_WT = p_rigid(q) + φ1(l) η n(q0): the rigid
/// columns (eq. 3.120 with l4 → l_f), q0's gaining φ1(l) η n'(q0), and φ1(l) n for η.
std::array<Vec3, 4> flexible_jacobian(const FiveBarParams& p, const FiveBarFlexibleMode& mode,
                                      const FiveBarJoints& q, double eta) {
  const FiveBarMatrix J = five_bar_jacobian(p, q);
  const double C0 = std::cos(q[0]), S0 = std::sin(q[0]);
  const double w = mode.tip_shape * eta;  // tip deflection, m
  return {{{J[0][0] - w * C0, J[1][0] - w * S0, J[2][0]},
           {J[0][1], J[1][1], J[2][1]},
           {J[0][2], J[1][2], J[2][2]},
           {-mode.tip_shape * S0, mode.tip_shape * C0, 0.0}}};
}

/// Solves the symmetric 3×3 system D a = b (Cramer's rule; D positive definite).
FiveBarJoints solve3(const FiveBarMatrix& D, const FiveBarJoints& b) {
  const double c00 = D[1][1] * D[2][2] - D[1][2] * D[2][1];
  const double c01 = D[1][2] * D[2][0] - D[1][0] * D[2][2];
  const double c02 = D[1][0] * D[2][1] - D[1][1] * D[2][0];
  const double det = D[0][0] * c00 + D[0][1] * c01 + D[0][2] * c02;
  const double c11 = D[0][0] * D[2][2] - D[0][2] * D[2][0];
  const double c12 = D[0][1] * D[2][0] - D[0][0] * D[2][1];
  const double c22 = D[0][0] * D[1][1] - D[0][1] * D[1][0];
  // D symmetric: the inverse is the cofactor matrix over det.
  return {(c00 * b[0] + c01 * b[1] + c02 * b[2]) / det,
          (c01 * b[0] + c11 * b[1] + c12 * b[2]) / det,
          (c02 * b[0] + c12 * b[1] + c22 * b[2]) / det};
}

}  // namespace

FiveBarFlexibleMode FiveBarFlexibleMode::from_beam(const HubPayloadBeamParams& beam, double zeta) {
  FiveBarFlexibleMode mode;
  mode.omega = hub_payload_first_frequency(beam);
  mode.zeta = zeta;
  mode.rho = beam.rho;
  mode.beta = clamped_free_participation(1, beam.L);
  mode.tip_shape = clamped_free_tip_value(1, beam.L);
  return mode;
}

std::string FiveBarFlexibleMode::validate() const {
  if (!positive(omega)) return bad_parameter("mode.omega", "must be finite and > 0", omega);
  if (!non_negative(zeta)) return bad_parameter("mode.zeta", "must be finite and >= 0", zeta);
  if (!positive(rho)) return bad_parameter("mode.rho", "must be finite and > 0", rho);
  if (!std::isfinite(beta)) return bad_parameter("mode.beta", "must be finite", beta);
  if (!std::isfinite(tip_shape)) return bad_parameter("mode.tip_shape", "must be finite", tip_shape);
  return {};
}

FiveBarJoints five_bar_home() { return {0.0, 0.5 * std::numbers::pi, std::numbers::pi}; }

FiveBarParams FiveBarParams::theoretical() {
  FiveBarParams p;
  p.alpha1 = 0.199;  // Table 5.5, x_e
  p.alpha2 = 0.032;  // Table 5.5, y_e
  p.J_hub = 0.677;   // §5.4.2, J0 (L2806); J_hub + α2 = 0.709 ≈ Table 5.5's z_e 0.708
  return p;
}

std::string FiveBarParams::validate() const {
  if (!positive(l1)) return bad_parameter("l1", "must be finite and > 0", l1);
  if (!positive(l_f)) return bad_parameter("l_f", "must be finite and > 0", l_f);
  if (!positive(alpha1)) return bad_parameter("alpha1", "must be finite and > 0", alpha1);
  if (!positive(alpha2)) return bad_parameter("alpha2", "must be finite and > 0", alpha2);
  if (!std::isfinite(alpha3)) return bad_parameter("alpha3", "must be finite", alpha3);
  // D's q1–q2 block [[α1, α3 C], [α3 C, α2]] must stay positive definite for every C in [−1, 1].
  if (alpha3 * alpha3 >= alpha1 * alpha2) {
    return bad_parameter("alpha3", "must satisfy alpha3^2 < alpha1 * alpha2 (positive-definite inertia)",
               alpha3);
  }
  if (!positive(J_hub)) return bad_parameter("J_hub", "must be finite and > 0", J_hub);
  // D00 = J_h + α1 C1² + α2 C2² + 2 α3 C1 C2 ≥ J_h − |α3| when the q1–q2 block is definite.
  for (std::size_t i = 0; i < 3; ++i) {
    const std::string suffix = kJointSuffix[i];
    const CoulombViscousFriction& f = friction[i];
    if (!non_negative(f.coulomb)) {
      return bad_parameter("friction" + suffix + ".coulomb", "must be finite and >= 0", f.coulomb);
    }
    if (!non_negative(f.viscous)) {
      return bad_parameter("friction" + suffix + ".viscous", "must be finite and >= 0", f.viscous);
    }
    if (!positive(f.stick_velocity)) {
      return bad_parameter("friction" + suffix + ".stick_velocity", "must be finite and > 0",
                 f.stick_velocity);
    }
    const double k = encoder_rad_per_count[i];
    if (!std::isfinite(k) || k == 0.0) {
      return bad_parameter("encoder_rad_per_count" + suffix, "must be finite and non-zero", k);
    }
    if (!positive(torque_limit[i])) {
      return bad_parameter("torque_limit" + suffix, "must be finite and > 0", torque_limit[i]);
    }
  }
  return {};
}

Vec3 five_bar_tip_position(const FiveBarParams& p, const FiveBarJoints& q) {
  const double rho = p.l1 * std::cos(q[1]) - p.l_f * std::cos(q[2]);
  return {rho * std::cos(q[0]), rho * std::sin(q[0]),
          p.l1 * std::sin(q[1]) - p.l_f * std::sin(q[2])};
}

FiveBarMatrix five_bar_jacobian(const FiveBarParams& p, const FiveBarJoints& q) {
  const double C0 = std::cos(q[0]), S0 = std::sin(q[0]);
  const double C1 = std::cos(q[1]), S1 = std::sin(q[1]);
  const double C2 = std::cos(q[2]), S2 = std::sin(q[2]);
  const double rho = p.l1 * C1 - p.l_f * C2;
  // Eq. 3.120 with l4 → l_f.
  return {{{-rho * S0, -p.l1 * S1 * C0, p.l_f * S2 * C0},
           {rho * C0, -p.l1 * S1 * S0, p.l_f * S2 * S0},
           {0.0, p.l1 * C1, -p.l_f * C2}}};
}

FiveBarJoints five_bar_joint_torque(const FiveBarParams& params, const FiveBarJoints& q,
                                    const Vec3& F_T_W) {
  const FiveBarMatrix J = five_bar_jacobian(params, q);
  FiveBarJoints tau{};
  for (std::size_t j = 0; j < 3; ++j) {
    tau[j] = J[0][j] * F_T_W.x + J[1][j] * F_T_W.y + J[2][j] * F_T_W.z;  // eq. 3.58
  }
  return tau;
}

bool five_bar_inverse_kinematics(const FiveBarParams& p, const Vec3& p_WT, FiveBarBranch branch,
                                 FiveBarJoints& q) {
  const double rho = std::hypot(p_WT.x, p_WT.y);
  if (!(rho > 0.0) || !std::isfinite(p_WT.z)) return false;
  const double D2 = rho * rho + p_WT.z * p_WT.z;
  const double cos_gamma = (D2 - p.l1 * p.l1 - p.l_f * p.l_f) / (2.0 * p.l1 * p.l_f);
  if (!(std::abs(cos_gamma) <= 1.0)) return false;
  const double magnitude = std::acos(cos_gamma);
  const double gamma = branch == FiveBarBranch::kElbowDown ? -magnitude : magnitude;
  const double q1 = std::atan2(p_WT.z, rho) -
                    std::atan2(p.l_f * std::sin(gamma), p.l1 + p.l_f * std::cos(gamma));
  q = {std::atan2(p_WT.y, p_WT.x), q1, q1 + gamma + std::numbers::pi};
  return true;
}

FiveBarPlant::FiveBarPlant(const FiveBarParams& params, const FiveBarState& initial,
                           const FiveBarPlantOptions& options)
    : params_(params), options_(options), state_(initial) {
  assert(params.validate().empty());
  // The hub's inertia with the mode eliminated, D00 − ρβ1², must stay positive; D00 ≥ J_h − |α3|.
  assert(!options.flexible_mode ||
         (options.mode.validate().empty() &&
          options.mode.rho * options.mode.beta * options.mode.beta <
              params.J_hub - std::abs(params.alpha3)));
}

void FiveBarPlant::step(const FiveBarJoints& tau_command, double dt) {
  step(tau_command, dt, [](const Vec3&, const Vec3&) { return Vec3{}; });
}

FiveBarMatrix FiveBarPlant::mass_matrix(const FiveBarJoints& q, double tip_mass) const {
  const FiveBarParams& p = params_;
  const double C1 = std::cos(q[1]), C2 = std::cos(q[2]);
  const double C21 = std::cos(q[2] - q[1]);
  const double rho = p.l1 * C1 - p.l_f * C2;
  // Eq. 4.10 plus the hub; a tip mass m adds m JᵀJ = m [[ρ², 0, 0], [0, l1², −l1 l_f C(2−1)],
  // [0, −l1 l_f C(2−1), l_f²]] (the columns of eq. 3.120).
  const double D00 = p.J_hub + p.alpha1 * C1 * C1 + p.alpha2 * C2 * C2 +
                     2.0 * p.alpha3 * C1 * C2 + tip_mass * rho * rho;
  const double D12 = (p.alpha3 - tip_mass * p.l1 * p.l_f) * C21;
  return {{{D00, 0.0, 0.0},
           {0.0, p.alpha1 + tip_mass * p.l1 * p.l1, D12},
           {0.0, D12, p.alpha2 + tip_mass * p.l_f * p.l_f}}};
}

FiveBarJoints FiveBarPlant::velocity_torques(const FiveBarState& s, double tip_mass) const {
  const FiveBarParams& p = params_;
  const double C1 = std::cos(s.q[1]), S1 = std::sin(s.q[1]);
  const double C2 = std::cos(s.q[2]), S2 = std::sin(s.q[2]);
  const double S21 = std::sin(s.q[2] - s.q[1]);
  const double w0 = s.qdot[0], w1 = s.qdot[1], w2 = s.qdot[2];
  // ∂D00/∂q1 and ∂D00/∂q2 of the linkage (eq. 4.10).
  const double dD00_dq1 = -2.0 * p.alpha1 * C1 * S1 - 2.0 * p.alpha3 * S1 * C2;
  const double dD00_dq2 = -2.0 * p.alpha2 * C2 * S2 - 2.0 * p.alpha3 * C1 * S2;
  // L2382 for α3 = 0 (first row: −2(α1 C1 S1 q̇1 + α2 C2 S2 q̇2) q̇0, then α1 C1 S1 q̇0² and
  // α2 C2 S2 q̇0²), with the α3 S(2−1) terms from Lagrange's equations.
  FiveBarJoints c{(dD00_dq1 * w1 + dD00_dq2 * w2) * w0,
                  -0.5 * dD00_dq1 * w0 * w0 - p.alpha3 * S21 * w2 * w2,
                  -0.5 * dD00_dq2 * w0 * w0 + p.alpha3 * S21 * w1 * w1};
  if (tip_mass != 0.0) {
    const FiveBarJoints bias = five_bar_joint_torque(p, s.q, tip_mass * tip_bias_acceleration(p, s));
    for (std::size_t i = 0; i < 3; ++i) c[i] += bias[i];
  }
  return c;
}

FiveBarJoints FiveBarPlant::non_friction_torque(const FiveBarState& s, const FiveBarJoints& tau,
                                                const Vec3& F_T_W, double tip_mass) const {
  FiveBarJoints out = five_bar_joint_torque(params_, s.q, F_T_W);
  const FiveBarJoints c = options_.coriolis ? velocity_torques(s, tip_mass) : FiveBarJoints{};
  for (std::size_t i = 0; i < 3; ++i) out[i] += tau[i] - c[i];
  return out;
}

FiveBarJoints FiveBarPlant::acceleration(const FiveBarState& s, const FiveBarJoints& tau,
                                         const Vec3& F_T_W, double tip_mass) const {
  FiveBarJoints net = non_friction_torque(s, tau, F_T_W, tip_mass);
  for (std::size_t i = 0; i < 3; ++i) {
    net[i] -= params_.friction[i].resisting(s.qdot[i], net[i]);
  }
  const FiveBarMatrix D = mass_matrix(s.q, tip_mass);
  // D is block-diagonal: q0 alone, then the 2×2 q1–q2 block (diagonal when α3 = 0 and no hand).
  const double det = D[1][1] * D[2][2] - D[1][2] * D[1][2];
  return {net[0] / D[0][0], (D[2][2] * net[1] - D[1][2] * net[2]) / det,
          (D[1][1] * net[2] - D[1][2] * net[1]) / det};
}

double FiveBarPlant::kinetic_energy(const FiveBarState& s, double tip_mass) const {
  const FiveBarMatrix D = mass_matrix(s.q, tip_mass);
  double energy = 0.0;
  for (std::size_t i = 0; i < 3; ++i) {
    for (std::size_t j = 0; j < 3; ++j) energy += s.qdot[i] * D[i][j] * s.qdot[j];
  }
  return 0.5 * energy;
}

void FiveBarPlant::tip_state(const FiveBarState& s, Vec3& p_WT, Vec3& v_WT) const {
  p_WT = five_bar_tip_position(params_, s.q);
  const FiveBarMatrix J = five_bar_jacobian(params_, s.q);
  v_WT = {J[0][0] * s.qdot[0] + J[0][1] * s.qdot[1] + J[0][2] * s.qdot[2],
          J[1][0] * s.qdot[0] + J[1][1] * s.qdot[1] + J[1][2] * s.qdot[2],
          J[2][0] * s.qdot[0] + J[2][1] * s.qdot[1] + J[2][2] * s.qdot[2]};
}

void FiveBarPlant::flexible_tip_state(const FiveBarState& s, const FiveBarModeState& m,
                                      Vec3& p_WT, Vec3& v_WT) const {
  const std::array<Vec3, 4> J = flexible_jacobian(params_, options_.mode, s.q, m.eta);
  p_WT = five_bar_tip_position(params_, s.q) +
         (options_.mode.tip_shape * m.eta) * deflection_direction(s.q[0]);
  v_WT = s.qdot[0] * J[0] + s.qdot[1] * J[1] + s.qdot[2] * J[2] + m.eta_dot * J[3];
}

void FiveBarPlant::physical_tip_state(Vec3& p_WT, Vec3& v_WT) const {
  if (options_.flexible_mode) {
    flexible_tip_state(state_, mode_, p_WT, v_WT);
  } else {
    tip_state(state_, p_WT, v_WT);
  }
}

FiveBarFlexibleMatrix FiveBarPlant::flexible_mass_matrix(const FiveBarJoints& q, double eta,
                                                         double tip_mass) const {
  const FiveBarFlexibleMode& mode = options_.mode;
  const FiveBarMatrix D = mass_matrix(q, 0.0);
  FiveBarFlexibleMatrix M{};
  for (std::size_t i = 0; i < 3; ++i) {
    for (std::size_t j = 0; j < 3; ++j) M[i][j] = D[i][j];
  }
  // Eq. 3.31 with n = 1: ρη² on the hub, ρβ1 between hub and mode, ρ on the mode.
  M[0][0] += mode.rho * eta * eta;
  M[0][3] = M[3][0] = mode.rho * mode.beta;
  M[3][3] = mode.rho;
  if (tip_mass != 0.0) {
    const std::array<Vec3, 4> J = flexible_jacobian(params_, mode, q, eta);
    for (std::size_t i = 0; i < 4; ++i) {
      for (std::size_t j = 0; j < 4; ++j) M[i][j] += tip_mass * dot(J[i], J[j]);
    }
  }
  return M;
}

FiveBarPlant::FlexibleSystem FiveBarPlant::flexible_system(const FiveBarState& s,
                                                           const FiveBarModeState& m,
                                                           const FiveBarJoints& tau,
                                                           const Vec3& F_T_W,
                                                           double tip_mass) const {
  const FiveBarFlexibleMode& mode = options_.mode;
  const FiveBarFlexibleMatrix M = flexible_mass_matrix(s.q, m.eta, tip_mass);
  const std::array<Vec3, 4> J = flexible_jacobian(params_, mode, s.q, m.eta);
  // Generalized forces: the motors, J_fᵀ F at the deflected tip, the mode's spring and damper
  // (ρω1² η of eq. 3.30 and the modal damping 2ζω1ρ η̇).
  double Q[4] = {tau[0] + dot(J[0], F_T_W), tau[1] + dot(J[1], F_T_W), tau[2] + dot(J[2], F_T_W),
                 dot(J[3], F_T_W) - mode.rho * mode.omega * mode.omega * m.eta -
                     2.0 * mode.zeta * mode.omega * mode.rho * m.eta_dot};
  if (options_.coriolis) {
    // The linkage's velocity terms (L2382), eq. 3.29's 2ρηη̇q̇0 and eq. 3.30's −ρηq̇0², and a tip
    // mass's m J_fᵀ (J̇_f ẋ), with p̈ = J_f ẍ + J̇_f ẋ:
    // J̇_f ẋ = J̇ q̇ + φ1(l) (2 η̇ q̇0 n'(q0) − η q̇0² n(q0)).
    const FiveBarJoints c = velocity_torques(s, 0.0);
    const double w0 = s.qdot[0];
    Q[0] -= c[0] + 2.0 * mode.rho * m.eta * m.eta_dot * w0;
    Q[1] -= c[1];
    Q[2] -= c[2];
    Q[3] += mode.rho * m.eta * w0 * w0;
    if (tip_mass != 0.0) {
      const double C0 = std::cos(s.q[0]), S0 = std::sin(s.q[0]);
      const Vec3 n{-S0, C0, 0.0}, dn{-C0, -S0, 0.0};
      const Vec3 bias = tip_bias_acceleration(params_, s) +
                        mode.tip_shape * (2.0 * m.eta_dot * w0 * dn - m.eta * w0 * w0 * n);
      for (std::size_t i = 0; i < 4; ++i) Q[i] -= tip_mass * dot(J[i], bias);
    }
  }
  FlexibleSystem out;
  out.m_etaeta = M[3][3];
  out.net_eta = Q[3];
  for (std::size_t i = 0; i < 3; ++i) {
    out.m_qeta[i] = M[i][3];
    out.net[i] = Q[i] - M[i][3] * Q[3] / M[3][3];
    for (std::size_t j = 0; j < 3; ++j) out.D[i][j] = M[i][j] - M[i][3] * M[j][3] / M[3][3];
  }
  return out;
}

FiveBarJoints FiveBarPlant::flexible_non_friction_torque(const FiveBarState& s,
                                                         const FiveBarModeState& m,
                                                         const FiveBarJoints& tau,
                                                         const Vec3& F_T_W, double tip_mass) const {
  return flexible_system(s, m, tau, F_T_W, tip_mass).net;
}

FiveBarFlexibleAcceleration FiveBarPlant::flexible_acceleration(const FiveBarState& s,
                                                                const FiveBarModeState& m,
                                                                const FiveBarJoints& tau,
                                                                const Vec3& F_T_W,
                                                                double tip_mass) const {
  const FlexibleSystem sys = flexible_system(s, m, tau, F_T_W, tip_mass);
  FiveBarJoints net = sys.net;
  for (std::size_t i = 0; i < 3; ++i) {
    net[i] -= params_.friction[i].resisting(s.qdot[i], net[i]);
  }
  FiveBarFlexibleAcceleration a;
  a.qddot = solve3(sys.D, net);
  a.eta_ddot = (sys.net_eta - sys.m_qeta[0] * a.qddot[0] - sys.m_qeta[1] * a.qddot[1] -
                sys.m_qeta[2] * a.qddot[2]) /
               sys.m_etaeta;
  return a;
}

double FiveBarPlant::flexible_energy(const FiveBarState& s, const FiveBarModeState& m,
                                     double tip_mass) const {
  const FiveBarFlexibleMatrix M = flexible_mass_matrix(s.q, m.eta, tip_mass);
  const double v[4] = {s.qdot[0], s.qdot[1], s.qdot[2], m.eta_dot};
  double kinetic = 0.0;
  for (std::size_t i = 0; i < 4; ++i) {
    for (std::size_t j = 0; j < 4; ++j) kinetic += v[i] * M[i][j] * v[j];
  }
  const FiveBarFlexibleMode& mode = options_.mode;
  return 0.5 * kinetic + 0.5 * mode.rho * mode.omega * mode.omega * m.eta * m.eta;
}

FiveBarJoints five_bar_encoder_reading(const FiveBarParams& params, const FiveBarJoints& q) {
  const FiveBarJoints home = five_bar_home();
  FiveBarJoints out{};
  for (std::size_t i = 0; i < 3; ++i) {
    const double k = params.encoder_rad_per_count[i];
    out[i] = home[i] + std::floor((q[i] - home[i]) / k) * k;
  }
  return out;
}

const FiveBarJoints& BackwardDifferenceVelocity::update(const FiveBarJoints& q, double dt) {
  const double a = std::exp(-cutoff * dt);
  for (std::size_t i = 0; i < 3; ++i) {
    const double raw = (q[i] - previous[i]) / dt;
    velocity[i] = a * velocity[i] + (1.0 - a) * raw;
    previous[i] = q[i];
  }
  return velocity;
}

}  // namespace haptic::engine
