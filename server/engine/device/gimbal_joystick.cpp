#include "engine/device/gimbal_joystick.hpp"
#include "engine/core/parameter_checks.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <sstream>

namespace haptic::engine {
namespace {

bool positive(double v) { return std::isfinite(v) && v > 0.0; }
bool non_negative(double v) { return std::isfinite(v) && v >= 0.0; }

/// A sub-step ended at rest: inside the stick band, or across zero (a fixed step jumps over a band
/// narrower than |q̈| h, and would then chatter around zero instead of sticking).
bool stopped(double before, double after, double stick_velocity) {
  return std::abs(after) < stick_velocity || (before > 0.0) != (after > 0.0) || after == 0.0;
}

/// A = √(1 − sin²θ sin²Φ) (eq. 3.19's A).
double gimbal_A(double st, double sp) { return std::sqrt(1.0 - st * st * sp * sp); }

}  // namespace

// ---------------------------------------------------------------------------------------------
// Kinematics.

Vec3 joystick_shaft_direction(double theta, double phi) {
  const double st = std::sin(theta), ct = std::cos(theta);
  const double sp = std::sin(phi), cp = std::cos(phi);
  const double inv_A = 1.0 / gimbal_A(st, sp);
  return {st * cp * inv_A, -sp * ct * inv_A, ct * cp * inv_A};  // eq. 3.4
}

Vec3 joystick_forward(const JoystickPose& q) {
  return q.R * joystick_shaft_direction(q.theta, q.phi);  // eq. 3.3
}

JoystickPose joystick_inverse(const Vec3& p_WT) {
  // Eq. 3.1: R = |x|, tan Φ = −R_y / R_z, tan θ = R_x / R_z.
  return {std::atan2(p_WT.x, p_WT.z), std::atan2(-p_WT.y, p_WT.z), norm(p_WT)};
}

JoystickMatrix joystick_jacobian_R(double theta, double phi, double R) {
  const double st = std::sin(theta), ct = std::cos(theta);
  const double sp = std::sin(phi), cp = std::cos(phi);
  const double A = gimbal_A(st, sp);
  const double A3 = A * A * A;
  const double k = R / A3;
  // Eq. 3.13 with R for rΨ and the shaft column divided by r; signs of (2,3), (3,1) corrected.
  return {{{k * ct * cp, -k * sp * st * ct * ct, st * cp / A},
           {k * sp * st * cp * cp, -k * ct * cp, -sp * ct / A},
           {-k * st * cp * cp * cp, -k * sp * ct * ct * ct, ct * cp / A}}};
}

JoystickMatrix joystick_jacobian(double theta, double phi, double psi, double r) {
  JoystickMatrix J = joystick_jacobian_R(theta, phi, r * psi);
  for (auto& row : J) row[2] *= r;  // ∂x/∂Ψ = r ∂x/∂R (eq. 3.12)
  return J;
}

double joystick_jacobian_determinant(double theta, double phi, double psi, double r) {
  const double A = gimbal_A(std::sin(theta), std::sin(phi));
  return -r * r * r * psi * psi * std::cos(theta) * std::cos(phi) / (A * A * A);  // eq. 3.15
}

JoystickMatrix joystick_jacobian_inverse(double theta, double phi, double psi, double r) {
  const double st = std::sin(theta), ct = std::cos(theta);
  const double sp = std::sin(phi), cp = std::cos(phi);
  const double A = gimbal_A(st, sp);
  const double R = r * psi;
  // Eq. 3.19.
  return {{{A * ct / (R * cp), 0.0, -A * st / (R * cp)},
           {0.0, -A * cp / (R * ct), -A * sp / (R * ct)},
           {st * cp / (A * r), -sp * ct / (A * r), ct * cp / (A * r)}}};
}

JoystickMatrix joystick_load_cell_rotation(double theta, double phi) {
  const double st = std::sin(theta), ct = std::cos(theta);
  const double sp = std::sin(phi), cp = std::cos(phi);
  const double A = gimbal_A(st, sp);
  // Eq. 3.10: rows n_mx (3.8), n_my (3.6), n_mz = n_s (3.5).
  return {{{ct / A, st * sp * cp / A, -cp * cp * st / A},
           {0.0, cp, sp},
           {st * cp / A, -sp * ct / A, ct * cp / A}}};
}

JoystickMatrix joystick_measured_force_to_torque(double theta, double phi, double psi, double r) {
  const double st = std::sin(theta), ct = std::cos(theta);
  const double sp = std::sin(phi), cp = std::cos(phi);
  const double A = gimbal_A(st, sp);
  const double R = r * psi;
  // Eq. 3.21 with the (2,1) sign corrected.
  return {{{R * cp / (A * A), 0.0, 0.0},
           {-R * st * sp * ct / (A * A), -R * ct / A, 0.0},
           {0.0, 0.0, r}}};
}

Vec3 joystick_multiply(const JoystickMatrix& m, const Vec3& v) {
  return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
          m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
          m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
}

Vec3 joystick_multiply_transposed(const JoystickMatrix& m, const Vec3& v) {
  return {m[0][0] * v.x + m[1][0] * v.y + m[2][0] * v.z,
          m[0][1] * v.x + m[1][1] * v.y + m[2][1] * v.z,
          m[0][2] * v.x + m[1][2] * v.y + m[2][2] * v.z};
}

// ---------------------------------------------------------------------------------------------
// Parameters.

std::string GimbalJoystickParams::validate() const {
  if (!positive(r)) return bad_parameter("r", "must be finite and > 0", r);
  if (!positive(R_min)) return bad_parameter("R_min", "must be finite and > 0", R_min);
  if (!(std::isfinite(R_max) && R_max > R_min)) return bad_parameter("R_max", "must be finite and > R_min", R_max);
  if (!(positive(gimbal_limit) && gimbal_limit < std::numbers::pi / 2.0)) {
    return bad_parameter("gimbal_limit", "must be in (0, pi/2) (det J = 0 at pi/2, eq. 3.15)", gimbal_limit);
  }
  if (!positive(I_theta)) return bad_parameter("I_theta", "must be finite and > 0", I_theta);
  if (!positive(I_phi)) return bad_parameter("I_phi", "must be finite and > 0", I_phi);
  if (!positive(M_m)) return bad_parameter("M_m", "must be finite and > 0", M_m);
  if (!positive(M_s)) return bad_parameter("M_s", "must be finite and > 0", M_s);
  if (!positive(k_t)) return bad_parameter("k_t", "must be finite and > 0", k_t);
  if (!non_negative(b_t)) return bad_parameter("b_t", "must be finite and >= 0", b_t);
  if (!non_negative(F_d)) return bad_parameter("F_d", "must be finite and >= 0", F_d);
  if (!non_negative(gimbal_friction)) {
    return bad_parameter("gimbal_friction", "must be finite and >= 0", gimbal_friction);
  }
  if (!positive(stick_velocity)) return bad_parameter("stick_velocity", "must be finite and > 0", stick_velocity);
  if (!positive(motor_time_constant)) {
    return bad_parameter("motor_time_constant", "must be finite and > 0", motor_time_constant);
  }
  if (!positive(brake_time_constant)) {
    return bad_parameter("brake_time_constant", "must be finite and > 0", brake_time_constant);
  }
  if (!positive(motor_limit_gimbal)) return bad_parameter("motor_limit_gimbal", "must be finite and > 0", motor_limit_gimbal);
  if (!positive(motor_limit_shaft)) return bad_parameter("motor_limit_shaft", "must be finite and > 0", motor_limit_shaft);
  if (!positive(brake_limit_gimbal)) return bad_parameter("brake_limit_gimbal", "must be finite and > 0", brake_limit_gimbal);
  if (!positive(brake_limit_shaft)) return bad_parameter("brake_limit_shaft", "must be finite and > 0", brake_limit_shaft);
  if (!(non_negative(brake_residual_gimbal) && brake_residual_gimbal <= brake_limit_gimbal)) {
    return bad_parameter("brake_residual_gimbal", "must be in [0, brake_limit_gimbal]", brake_residual_gimbal);
  }
  if (!(non_negative(brake_residual_shaft) && brake_residual_shaft <= brake_limit_shaft)) {
    return bad_parameter("brake_residual_shaft", "must be in [0, brake_limit_shaft]", brake_residual_shaft);
  }
  return {};
}

std::string JoystickActuatorCommand::validate(const GimbalJoystickParams& params) const {
  for (std::size_t i = 0; i < 3; ++i) {
    if (!std::isfinite(motor[i])) {
      return bad_parameter("motor[" + std::to_string(i) + "]", "must be finite", motor[i]);
    }
    const double limit = params.brake_limit(i);
    if (!(std::isfinite(brake[i]) && brake[i] >= 0.0 && brake[i] <= limit)) {
      std::ostringstream requirement;
      requirement << "must be in [0, " << limit << "]";
      return bad_parameter("brake[" + std::to_string(i) + "]", requirement.str().c_str(), brake[i]);
    }
  }
  return {};
}

// ---------------------------------------------------------------------------------------------
// Plant.

namespace js = joystick_state;

GimbalJoystickPlant::GimbalJoystickPlant(const GimbalJoystickParams& params,
                                         const IntegrationSettings& settings,
                                         const JoystickPose& initial)
    : params_(params), settings_(settings) {
  assert(params.validate().empty());
  state_[js::kTheta] = initial.theta;
  state_[js::kPhi] = initial.phi;
  state_[js::kXm] = initial.R;
  state_[js::kR] = initial.R;
  mass_ = {params.I_theta, params.I_phi, params.M_m, params.M_s};
}

void GimbalJoystickPlant::step(const JoystickActuatorCommand& command, double dt) {
  step(command, dt, [](const Vec3&, const Vec3&) { return Vec3{}; });
}

void GimbalJoystickPlant::prepare(const JoystickActuatorCommand& command, double hand_mass) {
  for (std::size_t i = 0; i < 3; ++i) {
    motor_command_[i] = saturate(command.motor[i], params_.motor_limit(i));
    brake_command_[i] = std::clamp(command.brake[i], 0.0, params_.brake_limit(i));
  }
  mass_ = {params_.I_theta, params_.I_phi, params_.M_m, params_.M_s};
  if (hand_mass > 0.0) {
    const JoystickMatrix J =
        joystick_jacobian_R(state_[js::kTheta], state_[js::kPhi], state_[js::kR]);
    for (std::size_t c = 0; c < 2; ++c) {
      mass_[c] += hand_mass * (J[0][c] * J[0][c] + J[1][c] * J[1][c] + J[2][c] * J[2][c]);
    }
    mass_[3] += hand_mass;  // |n_s|² = 1
  }
}

void GimbalJoystickPlant::handle_state(const JoystickState& x, Vec3& p_WT, Vec3& v_WT) const {
  const double theta = x[js::kTheta], phi = x[js::kPhi], R = x[js::kR];
  const JoystickMatrix J = joystick_jacobian_R(theta, phi, R);
  p_WT = R * Vec3{J[0][2], J[1][2], J[2][2]};  // x = R n_s
  v_WT = joystick_multiply(J, {x[js::kThetaDot], x[js::kPhiDot], x[js::kRDot]});
}

Vec3 GimbalJoystickPlant::measured_joints() const {
  return {state_[js::kTheta], state_[js::kPhi], state_[js::kXm] / params_.r};
}

Vec3 GimbalJoystickPlant::measured_joint_rates() const {
  return {state_[js::kThetaDot], state_[js::kPhiDot], state_[js::kXmDot] / params_.r};
}

std::array<double, 4> GimbalJoystickPlant::applied(const JoystickState& x,
                                                   const Vec3& F_hand_W) const {
  const JoystickMatrix J = joystick_jacobian_R(x[js::kTheta], x[js::kPhi], x[js::kR]);
  const Vec3 tau_hand = joystick_multiply_transposed(J, F_hand_W);  // eq. 3.18; z: F along n_s
  const double f_t = params_.k_t * (x[js::kXm] - x[js::kR]) +
                     params_.b_t * (x[js::kXmDot] - x[js::kRDot]);
  return {x[js::kMotor + 0] + tau_hand.x, x[js::kMotor + 1] + tau_hand.y,
          x[js::kMotor + 2] / params_.r - f_t, f_t + tau_hand.z};
}

std::array<double, 4> GimbalJoystickPlant::capacities(const JoystickState& x) const {
  const auto brake = [&](std::size_t i) {
    return std::max(x[js::kBrake + i], params_.brake_residual(i));
  };
  return {params_.gimbal_friction + brake(0), params_.gimbal_friction + brake(1),
          brake(2) / params_.r, params_.F_d};
}

JoystickState GimbalJoystickPlant::derivative(const JoystickState& x, const Vec3& F_hand_W) const {
  const std::array<double, 4> load = applied(x, F_hand_W);
  const std::array<double, 4> capacity = capacities(x);
  JoystickState d{};
  for (std::size_t i = 0; i < js::kPositions; ++i) {
    const double v = x[js::kPositions + i];
    const CoulombViscousFriction coulomb{capacity[i], 0.0, stick_band(capacity[i], i)};
    d[i] = v;
    d[js::kPositions + i] = (load[i] - coulomb.resisting(v, load[i])) / mass_[i];
  }
  for (std::size_t i = 0; i < 3; ++i) {
    d[js::kMotor + i] = (motor_command_[i] - x[js::kMotor + i]) / params_.motor_time_constant;
    d[js::kBrake + i] = (brake_command_[i] - x[js::kBrake + i]) / params_.brake_time_constant;
  }
  return d;
}

void GimbalJoystickPlant::settle(const std::array<double, 4>& before, const Vec3& F_hand_W) {
  const std::array<double, 4> load = applied(state_, F_hand_W);
  const std::array<double, 4> capacity = capacities(state_);
  for (std::size_t i = 0; i < js::kPositions; ++i) {
    double& v = state_[js::kPositions + i];
    if (stopped(before[i], v, stick_band(capacity[i], i)) && std::abs(load[i]) <= capacity[i]) {
      v = 0.0;
    }
  }
}

double GimbalJoystickPlant::stick_band(double capacity, std::size_t i) const {
  return std::max(params_.stick_velocity, capacity * h_ / mass_[i]);
}

// ---------------------------------------------------------------------------------------------
// The cable drive and the sleeve (eqs. 3.29–3.34).

double capstan_slip_torque(double r, double preload, double mu_beta) {
  return 2.0 * r * preload * std::tanh(mu_beta / 2.0);
}

double sleeve_shaft_force(double tau, double r, double preload, double nu_alpha) {
  return tau / r * std::cosh(nu_alpha) - 2.0 * preload * std::sinh(nu_alpha);
}

double sleeve_breakaway_torque(double r, double preload, double nu_alpha) {
  return 2.0 * r * preload * std::tanh(nu_alpha);
}

// ---------------------------------------------------------------------------------------------
// Eq. 3.38, cleaned.

std::string CableTransmissionParams::validate() const {
  if (!positive(m_s)) return bad_parameter("m_s", "must be finite and > 0", m_s);
  if (!positive(k)) return bad_parameter("k", "must be finite and > 0", k);
  if (!non_negative(F_d)) return bad_parameter("F_d", "must be finite and >= 0", F_d);
  if (!positive(r)) return bad_parameter("r", "must be finite and > 0", r);
  if (!non_negative(nu_alpha)) return bad_parameter("nu_alpha", "must be finite and >= 0", nu_alpha);
  if (!positive(stick_velocity)) return bad_parameter("stick_velocity", "must be finite and > 0", stick_velocity);
  return {};
}

double CableTransmissionParams::natural_frequency() const { return std::sqrt(k / m_s); }

CableTransmissionModel::CableTransmissionModel(const CableTransmissionParams& params,
                                               const IntegrationSettings& settings, double psi0,
                                               double psi_dot0)
    : params_(params), settings_(settings), x_{psi0, psi_dot0}, inertia_(params.m_s * params.r * params.r) {
  assert(params.validate().empty());
}

void CableTransmissionModel::step(double tau, double dt) {
  const CableTransmissionParams& p = params_;
  const std::uint32_t n = settings_.substeps > 0 ? settings_.substeps : 1;
  const double h = dt / static_cast<double>(n);
  // The stick band as in GimbalJoystickPlant: at least the speed friction removes in one step.
  const double band = std::max(p.stick_velocity, p.F_d * p.r * h / inertia_);
  const CoulombViscousFriction coulomb{p.F_d * p.r, 0.0, band};
  const double drive = tau * std::cosh(p.nu_alpha);
  const double k_rot = p.k * p.r * p.r;  // k r². Unit: N·m/rad.
  for (std::uint32_t s = 0; s < n; ++s) {
    const double before = x_[1];
    integrate_step<1>(settings_.method, x_, h, [&](const StateVector<2>& x) {
      const double load = drive - k_rot * x[0];
      return StateVector<2>{x[1], (load - coulomb.resisting(x[1], load)) / inertia_};
    });
    const double load = drive - k_rot * x_[0];
    if (stopped(before, x_[1], band) && std::abs(load) <= coulomb.coulomb) x_[1] = 0.0;
  }
}

}  // namespace haptic::engine
