#include "engine/device/parallel_2dof.hpp"
#include "engine/core/parameter_checks.hpp"

#include <cassert>
#include <cmath>
#include <limits>
#include <sstream>

namespace haptic::engine {
namespace {

using parallel_2dof::Matrix2;
using parallel_2dof::Planar;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double dot(const Planar& a, const Planar& b) { return a.x * b.x + a.y * b.y; }

/// Gᵀ diag(d, d) G, the pattern of M_x and B_x (eq. 2).
Matrix2 weighted_gram(const Matrix2& G, double d) {
  return {d * (G.a00 * G.a00 + G.a10 * G.a10), d * (G.a00 * G.a01 + G.a10 * G.a11),
          d * (G.a01 * G.a00 + G.a11 * G.a10), d * (G.a01 * G.a01 + G.a11 * G.a11)};
}

}  // namespace

std::string Parallel2DofParams::validate() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  const auto non_negative = [](double v) { return std::isfinite(v) && v >= 0.0; };
  if (!non_negative(base_separation)) {
    return bad_parameter("base_separation", "must be finite and >= 0", base_separation);
  }
  if (!positive(proximal_length)) {
    return bad_parameter("proximal_length", "must be finite and > 0", proximal_length);
  }
  if (!positive(distal_length)) {
    return bad_parameter("distal_length", "must be finite and > 0", distal_length);
  }
  if (!(proximal_length + distal_length > 0.5 * base_separation)) {
    return bad_parameter("base_separation", "must be < 2 (proximal_length + distal_length) for a workspace",
               base_separation);
  }
  if (!positive(joint_inertia)) {
    return bad_parameter("joint_inertia", "must be finite and > 0", joint_inertia);
  }
  if (!non_negative(end_effector_mass)) {
    return bad_parameter("end_effector_mass", "must be finite and >= 0", end_effector_mass);
  }
  if (!non_negative(joint_viscous)) {
    return bad_parameter("joint_viscous", "must be finite and >= 0", joint_viscous);
  }
  if (!non_negative(joint_coulomb)) {
    return bad_parameter("joint_coulomb", "must be finite and >= 0", joint_coulomb);
  }
  if (!positive(stick_velocity)) {
    return bad_parameter("stick_velocity", "must be finite and > 0", stick_velocity);
  }
  if (!positive(max_joint_torque)) {
    return bad_parameter("max_joint_torque", "must be finite and > 0", max_joint_torque);
  }
  if (integration.substeps < 1) {
    return bad_parameter("integration.substeps", "must be >= 1", static_cast<double>(integration.substeps));
  }
  return {};
}

Parallel2DofPlant::Parallel2DofPlant(const Parallel2DofParams& params, const Vec3& p_WT,
                                     const Vec3& v_WT)
    : params_(params),
      friction_{params.joint_coulomb, params.joint_viscous, params.stick_velocity},
      state_{p_WT.x, p_WT.y, v_WT.x, v_WT.y} {
  assert(params.validate().empty());
  [[maybe_unused]] Planar q;
  assert(inverse_kinematics({p_WT.x, p_WT.y}, q));
}

bool Parallel2DofPlant::inverse_kinematics(const Planar& x, Planar& q) const {
  const double l1 = params_.proximal_length;
  const double l2 = params_.distal_length;
  const double half = 0.5 * params_.base_separation;
  const auto leg = [&](double ax, double sign, double& qi) {
    const double dx = x.x - ax;
    const double dy = x.y;
    const double r = std::hypot(dx, dy);
    const double c = (l1 * l1 + r * r - l2 * l2) / (2.0 * l1 * r);
    if (!(r > 0.0) || !(c > -1.0 && c < 1.0)) {
      qi = kNaN;
      return false;
    }
    qi = std::atan2(dy, dx) + sign * std::acos(c);
    return true;
  };
  const bool ok1 = leg(-half, +1.0, q.x);
  const bool ok2 = leg(+half, -1.0, q.y);
  return ok1 && ok2;
}

bool Parallel2DofPlant::forward_kinematics(const Planar& q, Planar& x) const {
  const double l1 = params_.proximal_length;
  const double l2 = params_.distal_length;
  const double half = 0.5 * params_.base_separation;
  const Planar b1{-half + l1 * std::cos(q.x), l1 * std::sin(q.x)};
  const Planar b2{half + l1 * std::cos(q.y), l1 * std::sin(q.y)};
  const Planar d{b2.x - b1.x, b2.y - b1.y};
  const double dist = std::hypot(d.x, d.y);
  if (!(dist > 0.0) || !(dist < 2.0 * l2)) {
    x = {kNaN, kNaN};
    return false;
  }
  // E = midpoint + height · (B_1→B_2 turned +90°): the working mode's side.
  const double height = std::sqrt(l2 * l2 - 0.25 * dist * dist);
  x = {0.5 * (b1.x + b2.x) - height * d.y / dist, 0.5 * (b1.y + b2.y) + height * d.x / dist};
  return true;
}

Parallel2DofKinematics Parallel2DofPlant::kinematics(const Planar& x, const Planar& x_dot) const {
  const double l1 = params_.proximal_length;
  const double half = 0.5 * params_.base_separation;
  Parallel2DofKinematics k;
  inverse_kinematics(x, k.q);  // NaN out of reach, which then propagates
  const auto leg = [&](double ax, double qi, double& g0, double& g1, double& qdi, double& hi) {
    const Planar u{std::cos(qi), std::sin(qi)};
    const Planar u_perp{-u.y, u.x};
    const Planar e{x.x - ax - l1 * u.x, x.y - l1 * u.y};  // B_i → E, the distal link
    const double den = l1 * dot(e, u_perp);
    g0 = e.x / den;
    g1 = e.y / den;
    qdi = g0 * x_dot.x + g1 * x_dot.y;
    const Planar e_dot{x_dot.x - l1 * u_perp.x * qdi, x_dot.y - l1 * u_perp.y * qdi};
    hi = (l1 * dot(e, u) * qdi * qdi + dot(e_dot, e_dot)) / den;
  };
  leg(-half, k.q.x, k.G.a00, k.G.a01, k.q_dot.x, k.h.x);
  leg(+half, k.q.y, k.G.a10, k.G.a11, k.q_dot.y, k.h.y);
  return k;
}

Matrix2 Parallel2DofPlant::jacobian(const Planar& x) const {
  const Matrix2 G = kinematics(x, {}).G;
  const double inv = 1.0 / G.determinant();
  return {G.a11 * inv, -G.a01 * inv, -G.a10 * inv, G.a00 * inv};
}

Matrix2 Parallel2DofPlant::cartesian_inertia(const Planar& x, double added_mass) const {
  Matrix2 M = weighted_gram(kinematics(x, {}).G, params_.joint_inertia);
  M.a00 += params_.end_effector_mass + added_mass;
  M.a11 += params_.end_effector_mass + added_mass;
  return M;
}

Planar Parallel2DofPlant::cartesian_coriolis(const Planar& x, const Planar& x_dot) const {
  const Parallel2DofKinematics k = kinematics(x, x_dot);
  return k.G.transposed() * Planar{params_.joint_inertia * k.h.x, params_.joint_inertia * k.h.y};
}

Matrix2 Parallel2DofPlant::cartesian_damping(const Planar& x) const {
  return weighted_gram(kinematics(x, {}).G, params_.joint_viscous);
}

Planar Parallel2DofPlant::acceleration(const State& s, const Planar& tau,
                                       const Planar& f_external) const {
  const Parallel2DofKinematics k = kinematics({s[0], s[1]}, {s[2], s[3]});
  const double I = params_.joint_inertia;
  // Joint-side torques: the motors less friction (eq. 1's B q̇ + H(q̇)) less the inertial
  // velocity term I h that the closed chain's kinematics add (eq. 2's −M J^{-1} J̇ q̇).
  const Planar tau_net{tau.x - friction_.smooth(k.q_dot.x) - I * k.h.x,
                       tau.y - friction_.smooth(k.q_dot.y) - I * k.h.y};
  const Planar f = k.G.transposed() * tau_net;
  Matrix2 M = weighted_gram(k.G, I);
  M.a00 += params_.end_effector_mass + added_mass_;
  M.a11 += params_.end_effector_mass + added_mass_;
  return M.solve({f.x + f_external.x, f.y + f_external.y});
}

void Parallel2DofPlant::step(const Planar& tau, double dt) {
  step(tau, dt, [](const Vec3&, const Vec3&) { return Vec3{}; });
}

Planar Parallel2DofPlant::joint_torque(const Planar& force) const {
  // τ = Jᵀ F with J = G^{-1}: solve Gᵀ τ = F.
  return kinematics({state_[0], state_[1]}, {}).G.transposed().solve(force);
}

Planar Parallel2DofPlant::joint_angles() const {
  Planar q;
  inverse_kinematics({state_[0], state_[1]}, q);
  return q;
}

}  // namespace haptic::engine
