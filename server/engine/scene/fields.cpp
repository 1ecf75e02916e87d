#include "engine/scene/fields.hpp"
#include "engine/core/parameter_checks.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <sstream>

namespace haptic::engine {
namespace {

// Smallest accepted |axis_W|: below it the normalised direction is dominated by rounding.
constexpr double kMinAxisNorm = 1e-12;
// Largest accepted central-difference step; the workspace is ~0.1–0.3 m across.
constexpr double kMaxDifferenceStep = 1e-2;
// Relative asymmetry below which a Jacobian counts as symmetric (has a potential).
constexpr double kSymmetryTolerance = 1e-12;

double ipow(double x, int n) {
  double r = 1.0;
  for (int i = 0; i < n; ++i) r *= x;
  return r;
}

Vec3 unit(const Vec3& a) { return a * (1.0 / norm(a)); }

// Smoothstep s(t) = 3t² − 2t³ on [0, 1] and its slope 6t(1 − t) (zero at both ends).
double smoothstep(double t) { return t * t * (3.0 - 2.0 * t); }
double smoothstep_slope(double t) { return 6.0 * t * (1.0 - t); }

// ---- validation messages ---------------------------------------------------------------------

bool finite_positive(double v) { return std::isfinite(v) && v > 0.0; }
bool finite_non_negative(double v) { return std::isfinite(v) && v >= 0.0; }

std::string prefixed(const char* prefix, std::string message) {
  return message.empty() ? message : std::string(prefix) + "." + message;
}

}  // namespace

// ---- distance functions ----------------------------------------------------------------------

DistanceSample evaluate_distance(const DistanceSpec& d, const Vec3& p_WT) {
  const Vec3 delta = p_WT - d.origin_W;
  DistanceSample out;
  switch (d.kind) {
    case DistanceKind::kPoint:
    case DistanceKind::kSphere: {
      // f = |δ| (− R); ∇f = δ/|δ|, undefined at δ = 0.
      const double rho = norm(delta);
      out.f = d.kind == DistanceKind::kSphere ? rho - d.radius : rho;
      if (rho > 0.0) out.grad_f = delta * (1.0 / rho);
      break;
    }
    case DistanceKind::kLine: {
      // Perpendicular part e = δ − (δ·u)u; f = |e|, ∇f = e/|e|, undefined on the line.
      const Vec3 u = unit(d.axis_W);
      const Vec3 e = delta - dot(delta, u) * u;
      out.f = norm(e);
      if (out.f > 0.0) out.grad_f = e * (1.0 / out.f);
      break;
    }
    case DistanceKind::kPlane: {
      const Vec3 n = unit(d.axis_W);
      out.f = dot(delta, n);
      out.grad_f = n;
      break;
    }
  }
  return out;
}

double radial_fade(double rho, double radius, double fade_width) {
  assert(fade_width > 0.0 && fade_width <= radius);
  const double inner = radius - fade_width;
  if (rho <= inner) return 1.0;
  if (rho >= radius) return 0.0;
  return 1.0 - smoothstep((rho - inner) / fade_width);
}

// ---- potential fields (Russo eqs. 5.6, 5.7) --------------------------------------------------

PotentialProfile potential_profile(const PotentialFieldSpec& spec, double f) {
  const int n = spec.order;
  const double K = spec.gain;
  PotentialProfile out;
  if (spec.kind == PotentialKind::kPolynomial) {
    // Eq. 5.6 with (c − f)ⁿ: U = K aⁿ/n, dU/df = −K aⁿ⁻¹, a = c − f > 0.
    const double a = spec.offset - f;
    if (a <= 0.0) return out;
    const double a_n1 = ipow(a, n - 1);
    out.U = K * a_n1 * a / n;
    out.dU_df = -K * a_n1;
    return out;
  }
  // Eq. 5.7: U = K aⁿ/n, a = 1/f − 1/f0; dU/df = K aⁿ⁻¹ · (−1/f²).
  const double f0 = spec.influence_distance;
  if (f >= f0) return out;
  const double fm = spec.min_distance;
  const double fe = std::max(f, fm);
  const double a = 1.0 / fe - 1.0 / f0;
  const double a_n1 = ipow(a, n - 1);
  out.U = K * a_n1 * a / n;
  out.dU_df = -K * a_n1 / (fe * fe);
  if (f < fm) out.U += out.dU_df * (f - fm);  // tangent continuation below f_m
  return out;
}

FieldSample evaluate_field(const PotentialFieldSpec& spec, const Vec3& p_WT, const Vec3&) {
  FieldSample out;
  out.has_potential = true;
  const DistanceSample d = evaluate_distance(spec.distance, p_WT);
  const PotentialProfile profile = potential_profile(spec, d.f);
  out.U = profile.U;
  if (spec.gradient == GradientMethod::kAnalytic) {
    out.F_T_W = -profile.dU_df * d.grad_f;  // F = −∇U = −U′(f) ∇f (eq. 5.5, chain rule)
  } else {
    const auto U = [&spec](const Vec3& p) {
      return potential_profile(spec, evaluate_distance(spec.distance, p).f).U;
    };
    out.F_T_W = -central_difference_gradient(U, p_WT, spec.difference_step);
  }
  return out;
}

// ---- springs ---------------------------------------------------------------------------------

FieldSample evaluate_field(const SpringFieldSpec& spec, const Vec3& p_WT, const Vec3& v_WT) {
  const Vec3 delta = p_WT - spec.anchor.origin_W;
  Vec3 e;     // Displacement along the constrained directions. Unit: m.
  Vec3 v_c;   // Velocity along them (P v). Unit: m/s.
  double f = 0.0;  // |f| of the anchor's distance function. Unit: m.
  switch (spec.anchor.kind) {
    case DistanceKind::kPoint:
      e = delta;
      v_c = v_WT;
      f = norm(e);
      break;
    case DistanceKind::kLine: {
      const Vec3 u = unit(spec.anchor.axis_W);
      e = delta - dot(delta, u) * u;
      v_c = v_WT - dot(v_WT, u) * u;
      f = norm(e);
      break;
    }
    case DistanceKind::kPlane: {
      const Vec3 n = unit(spec.anchor.axis_W);
      const double s = dot(delta, n);
      e = s * n;
      v_c = dot(v_WT, n) * n;
      f = std::abs(s);
      break;
    }
    case DistanceKind::kSphere: {
      const double rho = norm(delta);
      f = std::abs(rho - spec.anchor.radius);
      if (rho > 0.0) {  // the radial direction is undefined at the centre: no force there
        const Vec3 r = delta * (1.0 / rho);
        e = (rho - spec.anchor.radius) * r;
        v_c = dot(v_WT, r) * r;
      }
      break;
    }
  }
  const double k = spec.stiffness;
  FieldSample out;
  out.has_potential = true;
  const double F_max = spec.max_force;
  out.F_T_W = clip_norm(-k * e - spec.damping * v_c, F_max);
  // Potential of the clipped elastic force magnitude min(k f, F_max).
  if (F_max > 0.0 && k * f > F_max) {
    out.U = F_max * f - F_max * F_max / (2.0 * k);
  } else {
    out.U = 0.5 * k * f * f;
  }
  return out;
}

// ---- first-order field -----------------------------------------------------------------------

FieldSample evaluate_field(const LinearFieldSpec& spec, const Vec3& p_WT, const Vec3&) {
  const Vec3 delta = p_WT - spec.origin_W;
  const double rho = norm(delta);
  FieldSample out;
  const double w = radial_fade(rho, spec.radius, spec.fade_width);
  if (w == 0.0) return out;
  const std::array<Vec3, 3>& K = spec.jacobian;
  const Vec3 K_delta{dot(K[0], delta), dot(K[1], delta), dot(K[2], delta)};
  out.F_T_W = w * (spec.force_W + K_delta);
  const double scale = std::max({std::abs(K[0].x), std::abs(K[0].y), std::abs(K[0].z),
                                 std::abs(K[1].x), std::abs(K[1].y), std::abs(K[1].z),
                                 std::abs(K[2].x), std::abs(K[2].y), std::abs(K[2].z)});
  const double tolerance = kSymmetryTolerance * scale;
  const bool symmetric = std::abs(K[0].y - K[1].x) <= tolerance &&
                         std::abs(K[0].z - K[2].x) <= tolerance &&
                         std::abs(K[1].z - K[2].y) <= tolerance;
  if (symmetric && rho <= spec.radius - spec.fade_width) {
    // F = F0 + Kδ = −∇U with U = −F0·δ − ½ δᵀKδ (K symmetric).
    out.U = -dot(spec.force_W, delta) - 0.5 * dot(delta, K_delta);
    out.has_potential = true;
  }
  return out;
}

// ---- viscous field ---------------------------------------------------------------------------

FieldSample evaluate_field(const ViscousFieldSpec& spec, const Vec3& p_WT, const Vec3& v_WT) {
  double w = 1.0;
  if (spec.radius > 0.0) w = radial_fade(norm(p_WT - spec.center_W), spec.radius, spec.fade_width);
  FieldSample out;
  out.F_T_W = (-w * spec.damping) * v_WT;
  return out;
}

// ---- detent ----------------------------------------------------------------------------------

PotentialProfile detent_profile(double depth, double radius, double rim_height, double rim_width,
                                double rho) {
  const double D = depth;
  const double H = rim_height;
  const double R = radius;
  const double w = rim_width;
  PotentialProfile out;
  if (rho <= R) {
    const double t = rho / R;
    out.U = -D + (D + H) * smoothstep(t);
    out.dU_df = (D + H) * smoothstep_slope(t) / R;
  } else if (rho < R + w) {
    const double t = (rho - R) / w;
    out.U = H * (1.0 - smoothstep(t));
    out.dU_df = -H * smoothstep_slope(t) / w;
  }
  return out;
}

FieldSample evaluate_field(const DetentFieldSpec& spec, const Vec3& p_WT, const Vec3&) {
  const DistanceSample d = evaluate_distance(spec.distance, p_WT);
  // ρ = |f|, ∇ρ = sign(f) ∇f (U′(0) = 0, so the sign at f = 0 does not matter).
  const double rho = std::abs(d.f);
  const Vec3 grad_rho = d.f < 0.0 ? -d.grad_f : d.grad_f;
  const PotentialProfile profile =
      detent_profile(spec.depth, spec.radius, spec.rim_height, spec.rim_width, rho);
  FieldSample out;
  out.U = profile.U;
  out.has_potential = true;
  out.F_T_W = -profile.dU_df * grad_rho;
  return out;
}

// ---- any field -------------------------------------------------------------------------------

FieldSample evaluate_field(const EnergyFieldSpec& spec, const Vec3& p_WT, const Vec3& v_WT) {
  return std::visit([&](const auto& s) { return evaluate_field(s, p_WT, v_WT); }, spec);
}

// ---- validation ------------------------------------------------------------------------------

std::string validate_field(const DistanceSpec& spec) {
  if (spec.kind != DistanceKind::kPoint && spec.kind != DistanceKind::kLine &&
      spec.kind != DistanceKind::kPlane && spec.kind != DistanceKind::kSphere) {
    return bad_parameter("kind", "must be point, line, plane or sphere",
               static_cast<double>(static_cast<int>(spec.kind)));
  }
  if (!is_finite(spec.origin_W)) return bad_parameter("origin_W", "must be finite", spec.origin_W);
  if (spec.kind == DistanceKind::kLine || spec.kind == DistanceKind::kPlane) {
    if (!is_finite(spec.axis_W) || !(norm(spec.axis_W) > kMinAxisNorm)) {
      return bad_parameter("axis_W", "must be finite with norm > 1e-12", spec.axis_W);
    }
  }
  if (spec.kind == DistanceKind::kSphere && !finite_positive(spec.radius)) {
    return bad_parameter("radius", "must be finite and > 0", spec.radius);
  }
  return {};
}

std::string validate_field(const PotentialFieldSpec& spec) {
  if (std::string m = prefixed("distance", validate_field(spec.distance)); !m.empty()) return m;
  if (spec.kind != PotentialKind::kPolynomial && spec.kind != PotentialKind::kKhatib) {
    return bad_parameter("kind", "must be polynomial or khatib",
               static_cast<double>(static_cast<int>(spec.kind)));
  }
  if (spec.order < 2 || spec.order > kMaxPotentialOrder) {
    return bad_parameter("order", "must be an integer in [2, 8]", static_cast<double>(spec.order));
  }
  if (!finite_non_negative(spec.gain)) return bad_parameter("gain", "must be finite and >= 0", spec.gain);
  if (spec.gradient != GradientMethod::kAnalytic &&
      spec.gradient != GradientMethod::kCentralDifference) {
    return bad_parameter("gradient", "must be analytic or central_difference",
               static_cast<double>(static_cast<int>(spec.gradient)));
  }
  if (!finite_positive(spec.difference_step) || spec.difference_step > kMaxDifferenceStep) {
    return bad_parameter("difference_step", "must be finite, > 0 and <= 0.01", spec.difference_step);
  }
  if (spec.kind == PotentialKind::kPolynomial) {
    if (!std::isfinite(spec.offset) || std::abs(spec.offset) > kMaxPotentialReach) {
      return bad_parameter("offset", "must be finite and within ±100 m", spec.offset);
    }
    // The force grows as (c − f)ⁿ⁻¹ without bound: it must stay finite wherever a tool can be
    // (every distance function here is within kMaxPotentialReach of any reachable point).
    const PotentialProfile farthest = potential_profile(spec, -kMaxPotentialReach);
    if (!std::isfinite(farthest.U) || !std::isfinite(farthest.dU_df)) {
      return bad_parameter("gain", "too large: the force 100 m inside the surface overflows", spec.gain);
    }
    return {};
  }
  // Khatib: U and its gradient are unbounded as f → 0 (eq. 5.7); admitted only with the cap.
  if (!finite_positive(spec.influence_distance)) {
    return bad_parameter("influence_distance", "must be finite and > 0", spec.influence_distance);
  }
  if (!finite_positive(spec.min_distance) || spec.min_distance >= spec.influence_distance) {
    return bad_parameter("min_distance", "must be finite, > 0 and < influence_distance", spec.min_distance);
  }
  const PotentialProfile at_min = potential_profile(spec, spec.min_distance);
  if (!std::isfinite(at_min.U) || !std::isfinite(at_min.dU_df)) {
    return bad_parameter("min_distance", "too small: the force there overflows", spec.min_distance);
  }
  return {};
}

std::string validate_field(const SpringFieldSpec& spec) {
  if (std::string m = prefixed("anchor", validate_field(spec.anchor)); !m.empty()) return m;
  if (!finite_non_negative(spec.stiffness)) {
    return bad_parameter("stiffness", "must be finite and >= 0", spec.stiffness);
  }
  if (!finite_non_negative(spec.damping)) {
    return bad_parameter("damping", "must be finite and >= 0", spec.damping);
  }
  if (!finite_non_negative(spec.max_force)) {
    return bad_parameter("max_force", "must be finite and >= 0", spec.max_force);
  }
  return {};
}

std::string validate_field(const LinearFieldSpec& spec) {
  if (!is_finite(spec.origin_W)) return bad_parameter("origin_W", "must be finite", spec.origin_W);
  if (!is_finite(spec.force_W)) return bad_parameter("force_W", "must be finite", spec.force_W);
  static constexpr const char* kRows[] = {"jacobian[0]", "jacobian[1]", "jacobian[2]"};
  for (int i = 0; i < 3; ++i) {
    if (!is_finite(spec.jacobian[i])) return bad_parameter(kRows[i], "must be finite", spec.jacobian[i]);
  }
  if (!finite_positive(spec.radius)) return bad_parameter("radius", "must be finite and > 0", spec.radius);
  if (!finite_positive(spec.fade_width) || spec.fade_width > spec.radius) {
    return bad_parameter("fade_width", "must be finite, > 0 and <= radius", spec.fade_width);
  }
  return {};
}

std::string validate_field(const ViscousFieldSpec& spec) {
  if (!finite_non_negative(spec.damping)) {
    return bad_parameter("damping", "must be finite and >= 0", spec.damping);
  }
  if (!is_finite(spec.center_W)) return bad_parameter("center_W", "must be finite", spec.center_W);
  if (!finite_non_negative(spec.radius)) {
    return bad_parameter("radius", "must be finite and >= 0 (0: everywhere)", spec.radius);
  }
  if (!std::isfinite(spec.fade_width)) {
    return bad_parameter("fade_width", "must be finite", spec.fade_width);
  }
  if (spec.radius > 0.0 && (!(spec.fade_width > 0.0) || spec.fade_width > spec.radius)) {
    return bad_parameter("fade_width", "must be > 0 and <= radius when radius > 0", spec.fade_width);
  }
  return {};
}

std::string validate_field(const DetentFieldSpec& spec) {
  if (std::string m = prefixed("distance", validate_field(spec.distance)); !m.empty()) return m;
  if (!finite_positive(spec.depth)) return bad_parameter("depth", "must be finite and > 0", spec.depth);
  if (!finite_positive(spec.radius)) return bad_parameter("radius", "must be finite and > 0", spec.radius);
  if (!finite_non_negative(spec.rim_height)) {
    return bad_parameter("rim_height", "must be finite and >= 0", spec.rim_height);
  }
  if (!finite_positive(spec.rim_width)) {
    return bad_parameter("rim_width", "must be finite and > 0", spec.rim_width);
  }
  return {};
}

std::string validate_field(const EnergyFieldSpec& spec) {
  return std::visit([](const auto& s) { return validate_field(s); }, spec);
}

// ---- energy bookkeeping ----------------------------------------------------------------------


}  // namespace haptic::engine
