#include "engine/device/dc_motor_plant.hpp"
#include "engine/core/parameter_checks.hpp"

#include <cassert>
#include <cmath>
#include <sstream>

namespace haptic::engine {
std::string DcMotorParams::validate() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  const auto non_negative = [](double v) { return std::isfinite(v) && v >= 0.0; };
  const auto unit_interval = [](double v) { return std::isfinite(v) && v > 0.0 && v <= 1.0; };
  if (!positive(R_m)) return bad_parameter("R_m", "must be finite and > 0", R_m);
  if (!positive(L_m)) return bad_parameter("L_m", "must be finite and > 0", L_m);
  if (!positive(k_m)) return bad_parameter("k_m", "must be finite and > 0", k_m);
  if (!positive(k_b)) return bad_parameter("k_b", "must be finite and > 0", k_b);
  if (!positive(J_m)) return bad_parameter("J_m", "must be finite and > 0", J_m);
  if (!non_negative(B_m)) return bad_parameter("B_m", "must be finite and >= 0", B_m);
  if (!unit_interval(r)) return bad_parameter("r", "must be in (0, 1]", r);
  if (!unit_interval(eta)) return bad_parameter("eta", "must be in (0, 1]", eta);
  if (!non_negative(I_zz)) return bad_parameter("I_zz", "must be finite and >= 0", I_zz);
  if (!non_negative(m)) return bad_parameter("m", "must be finite and >= 0", m);
  if (!non_negative(l_c)) return bad_parameter("l_c", "must be finite and >= 0", l_c);
  if (!non_negative(l)) return bad_parameter("l", "must be finite and >= 0", l);
  if (!std::isfinite(alpha_c)) return bad_parameter("alpha_c", "must be finite", alpha_c);
  if (!non_negative(g)) return bad_parameter("g", "must be finite and >= 0", g);
  return {};
}

void dc_motor_end_point(const DcMotorParams& p, double theta_m, double omega_m, Vec3& p_WT,
                        Vec3& v_WT) {
  const double phi = p.r * theta_m + p.alpha_c;
  const double omega_L = p.r * omega_m;
  p_WT = {p.l * std::cos(phi), p.l * std::sin(phi), 0.0};
  v_WT = {-p.l * std::sin(phi) * omega_L, p.l * std::cos(phi) * omega_L, 0.0};
}

double external_joint_torque(const DcMotorParams& params, double theta_L,
                             const ExternalWrench& F_e) {
  // Eq. 4.3: the rows of J for f_ez, n_ex and n_ey are zero.
  const double angle = theta_L + params.alpha_c;
  return params.l * (-F_e.f_E_W.x * std::sin(angle) + F_e.f_E_W.y * std::cos(angle)) + F_e.n_W.z;
}

DcMotorPlant::DcMotorPlant(const DcMotorParams& params, DcMotorModel model,
                           const DcMotorState& initial, IntegrationSettings integration)
    : params_(params),
      model_(model),
      state_(initial),
      integration_(integration),
      inv_J_eff_(1.0 / params.J_eff()),
      gear_(params.r / params.eta) {
  assert(params.validate().empty());
  if (integration_.substeps == 0) integration_.substeps = 1;
  if (model_ == DcMotorModel::kWithoutInductance) state_.i = algebraic_current(state_, 0.0);
}

void DcMotorPlant::step(double u_m, double dt) {
  step(u_m, dt, [](double, double) { return ExternalWrench{}; });
}

std::uint32_t DcMotorPlant::substeps_for(double dt) const {
  const std::uint32_t configured = integration_.substeps;
  if (model_ == DcMotorModel::kWithoutInductance) return configured;
  const double needed = std::ceil(dt / (0.5 * params_.t_e()));
  return needed > static_cast<double>(configured) ? static_cast<std::uint32_t>(needed) : configured;
}

DcMotorPlant::Derivative DcMotorPlant::derivative(const DcMotorState& s, double u_m,
                                                  double tau_e) const {
  const DcMotorParams& p = params_;
  // Load torque reflected to the motor axis, less its inertial part (eqs. 3.8, 4.6).
  const double load = gear_ * (p.gravity_torque(s.theta_m) - tau_e);
  Derivative d;
  d.theta_m = s.omega_m;
  if (model_ == DcMotorModel::kWithInductance) {
    d.omega_m = (p.k_m * s.i - p.B_m * s.omega_m - load) * inv_J_eff_;   // eqs. 2.3, 2.4b, 3.10a
    d.i = (u_m - p.R_m * s.i - p.k_b * s.omega_m) / p.L_m;              // eqs. 2.1, 2.4a
  } else {
    d.omega_m = (p.k_m / p.R_m * u_m - p.B() * s.omega_m - load) * inv_J_eff_;  // eq. 3.9
  }
  return d;
}

double DcMotorPlant::algebraic_current(const DcMotorState& s, double u_m) const {
  return (u_m - params_.k_b * s.omega_m) / params_.R_m;  // eq. 2.6
}

}  // namespace haptic::engine
