#pragma once
// Energy fields: forces derived from potentials over distance functions (Russo 1990 ch. 5,
// eqs. 5.5–5.7), springs to a point, line or plane, a first-order (linearised) field, a viscous
// field and a detent, plus an energy meter for the work a field does on the tool.
//
// Each field is a plain spec struct. validate_field() runs once, off the loop, and returns "" or one
// message naming the bad parameter; evaluate_field() runs per tick on a validated spec, allocates
// nothing and never throws. Frames per docs/architecture.md: p_WT, v_WT are the tool's position
// (m) and velocity (m/s) in W; F_T_W is the force on the tool in W (N).
//
// Sign convention: F = −∇U (Russo eq. 5.5); non-conservative terms (damping, viscous fields) are
// added separately, as the thesis prescribes below eq. 5.5.

#include <array>
#include <cstdint>
#include <string>
#include <variant>

#include "engine/core/vec3.hpp"

namespace haptic::engine {

// ---------------------------------------------------------------------------------------------
// Distance functions f(p). Unit: m.

enum class DistanceKind : std::uint8_t {
  kPoint,   // f = |p − origin| (≥ 0).
  kLine,    // f = distance from the line through origin along axis (≥ 0).
  kPlane,   // f = (p − origin)·n̂, signed: > 0 on the side the normal points to.
  kSphere,  // f = |p − origin| − radius, signed: < 0 inside the sphere.
};

/// A distance function in W. Build with point_distance(), line_distance(), plane_distance() or
/// sphere_distance().
struct DistanceSpec {
  DistanceKind kind = DistanceKind::kPoint;
  Vec3 origin_W;          // The point; a point on the line or plane; the sphere's centre. Unit: m.
  Vec3 axis_W{0, 0, 1};   // kLine: direction; kPlane: normal. Non-zero; normalised on use.
  double radius = 0.0;    // kSphere only. Unit: m. > 0.
};

constexpr DistanceSpec point_distance(const Vec3& point_W) {
  return {DistanceKind::kPoint, point_W, {0, 0, 1}, 0.0};
}
constexpr DistanceSpec line_distance(const Vec3& point_W, const Vec3& direction_W) {
  return {DistanceKind::kLine, point_W, direction_W, 0.0};
}
constexpr DistanceSpec plane_distance(const Vec3& point_W, const Vec3& normal_W) {
  return {DistanceKind::kPlane, point_W, normal_W, 0.0};
}
constexpr DistanceSpec sphere_distance(const Vec3& center_W, double radius) {
  return {DistanceKind::kSphere, center_W, {0, 0, 1}, radius};
}

/// f(p) and its analytic gradient ∇f (dimensionless; a unit vector wherever f is differentiable).
/// Where ∇f is undefined (on the point, on the line, at the sphere's centre) grad_f is zero, so
/// anything built on it gives a finite, direction-free value there instead of NaN.
struct DistanceSample {
  double f = 0.0;  // Unit: m.
  Vec3 grad_f;     // Unit: 1.
};

DistanceSample evaluate_distance(const DistanceSpec& distance, const Vec3& p_WT);

// ---------------------------------------------------------------------------------------------
// What every field returns.

struct FieldSample {
  Vec3 F_T_W;                  // Force on the tool, in W. Unit: N.
  double U = 0.0;              // Potential energy stored in the field. Unit: J. Valid only if:
  bool has_potential = false;  // the force's conservative part is −∇U at this point.
};

/// Central-difference gradient of a scalar field (Russo eq. 5.7, second equation; error O(h²)):
/// ∂U/∂x ≈ (U(x + h) − U(x − h)) / 2h per axis. U is any callable double(const Vec3&); h in m.
/// Six evaluations; no allocation.
template <typename Potential>
Vec3 central_difference_gradient(const Potential& U, const Vec3& p, double h) {
  const double inv = 1.0 / (2.0 * h);
  return {(U(Vec3{p.x + h, p.y, p.z}) - U(Vec3{p.x - h, p.y, p.z})) * inv,
          (U(Vec3{p.x, p.y + h, p.z}) - U(Vec3{p.x, p.y - h, p.z})) * inv,
          (U(Vec3{p.x, p.y, p.z + h}) - U(Vec3{p.x, p.y, p.z - h})) * inv};
}

/// C¹ radial fade: 1 for rho ≤ radius − fade_width, 0 for rho ≥ radius, and between them
/// 1 − s(t) with the smoothstep s(t) = 3t² − 2t³, t = (rho − radius + fade_width) / fade_width,
/// whose slope is zero at both ends. Requires 0 < fade_width ≤ radius.
double radial_fade(double rho, double radius, double fade_width);

// ---------------------------------------------------------------------------------------------
// Potential fields over a distance function (Russo eqs. 5.6 and 5.7).

enum class PotentialKind : std::uint8_t {
  /// U = (1/n) K (c − f)ⁿ where f < c, else 0. This is eq. 5.6 written with (c − f) so that U ≥ 0
  /// and the force pushes toward larger f for every n; for even n it is eq. 5.6 exactly (for odd
  /// n, eq. 5.6 as printed gives U < 0 and a force that pulls into the object). n = 2 is the
  /// linear spring law F = K (c − f) ∇f. K: Unit J/mⁿ (= N/mⁿ⁻¹).
  kPolynomial,
  /// Khatib's repulsive field, eq. 5.7: U = (1/n) K (1/f − 1/f0)ⁿ for f < f0, else 0; U → ∞ as
  /// f → 0 (the surface). Below min_distance (f_m) the potential continues along its tangent,
  /// U(f) = U(f_m) + U′(f_m)(f − f_m): U stays C¹ (the force continuous) and conservative, the
  /// force is capped at its value at f_m and is finite at and through the surface. K: Unit J·mⁿ.
  kKhatib,
};

enum class GradientMethod : std::uint8_t {
  kAnalytic,           // Chain rule: ∇U = U′(f) ∇f.
  kCentralDifference,  // Russo eq. 5.7 (second), step difference_step.
};

inline constexpr int kMaxPotentialOrder = 8;
/// Farther than any tool can be from a potential's surface: scene positions are within ±10 m
/// (schema::SceneLimits), so no distance function can exceed this. A polynomial potential's offset
/// must be within it, and its force finite at it. Unit: m.
inline constexpr double kMaxPotentialReach = 100.0;

struct PotentialFieldSpec {
  DistanceSpec distance;
  PotentialKind kind = PotentialKind::kPolynomial;
  int order = 2;                     // n. 2 ≤ n ≤ kMaxPotentialOrder.
  double gain = 0.0;                 // K_n. Unit: see PotentialKind. ≥ 0.
  double offset = 0.0;               // c, kPolynomial only: active where f < c. Unit: m.
  double influence_distance = 0.0;   // f0, kKhatib only: active where f < f0. Unit: m. > 0.
  double min_distance = 0.0;         // f_m, kKhatib only. Unit: m. 0 < f_m < f0.
  GradientMethod gradient = GradientMethod::kAnalytic;
  double difference_step = 1e-6;     // h for kCentralDifference. Unit: m. 0 < h ≤ 0.01.
};

/// U(f) and dU/df of the potential's scalar profile (Unit: J and J/m), before the chain rule.
struct PotentialProfile {
  double U = 0.0;
  double dU_df = 0.0;
};
PotentialProfile potential_profile(const PotentialFieldSpec& spec, double f);

/// F = −∇U, U. Always has_potential.
FieldSample evaluate_field(const PotentialFieldSpec& spec, const Vec3& p_WT, const Vec3& v_WT);

// ---------------------------------------------------------------------------------------------
// Springs to a point, a line, a plane (or a sphere's surface).

/// U = ½ k f², elastic force F_e = −k f ∇f = −k e, with e the displacement from the anchor along
/// the constrained directions: all three for a point, the two normal to a line, the plane's
/// normal, the radial direction for a sphere's surface (a bilateral spring: it pulls from both
/// sides). Damping acts along the same constrained directions only: F_d = −b P v, P the projector
/// onto them. With max_force > 0 the total F = F_e + F_d is scaled down to |F| ≤ max_force.
/// U reported is the potential of the clipped elastic force: ½ k f² while k|f| ≤ F_max, else
/// F_max |f| − F_max² / 2k; it is exact for b = 0 (the clipped spring is still conservative).
/// At a degenerate point (on a point anchor or line: e = 0; at a sphere anchor's centre) the
/// elastic force is zero (there the sphere's direction is undefined).
struct SpringFieldSpec {
  DistanceSpec anchor;       // kPoint, kLine, kPlane or kSphere.
  double stiffness = 0.0;    // k. Unit: N/m. ≥ 0.
  double damping = 0.0;      // b. Unit: N·s/m. ≥ 0.
  double max_force = 0.0;    // Unit: N. ≥ 0; 0: no clip.
};

FieldSample evaluate_field(const SpringFieldSpec& spec, const Vec3& p_WT, const Vec3& v_WT);

// ---------------------------------------------------------------------------------------------
// First-order (linearised) field, as a slow client would send it: a force and its Jacobian about
// a point (the first-order Taylor model of the client's field; Russo ch. 5's local models).

/// F = w(ρ) (F0 + K (p − x0)), ρ = |p − x0|, w = radial_fade(ρ, radius, fade_width): exactly the
/// linear model for ρ ≤ radius − fade_width, fading C¹ to zero across the outer fade_width, zero
/// beyond radius. The faded field is not conservative even for symmetric K (curl(w ∇U0) =
/// ∇w × ∇U0 ≠ 0), and a non-symmetric K has no potential anywhere. So U is reported only where it
/// is exact: for symmetric K (|K_ij − K_ji| ≤ 1e-12 max|K|) inside the unfaded core, U =
/// −F0·δ − ½ δᵀKδ with δ = p − x0 (U = 0 at x0). Elsewhere has_potential is false; the work done
/// is what EnergyMeter measures.
struct LinearFieldSpec {
  Vec3 origin_W;                  // x0. Unit: m.
  Vec3 force_W;                   // F0, the force at x0. Unit: N.
  std::array<Vec3, 3> jacobian{}; // K = ∂F/∂p, row i: ∂F_i/∂p. Unit: N/m.
  double radius = 0.0;            // r, validity radius. Unit: m. > 0.
  double fade_width = 0.0;        // Unit: m. 0 < fade_width ≤ radius.
};

FieldSample evaluate_field(const LinearFieldSpec& spec, const Vec3& p_WT, const Vec3& v_WT);

// ---------------------------------------------------------------------------------------------
// Viscous field.

/// F = −w B v: everywhere (radius = 0, w = 1) or inside a sphere of influence with the same C¹
/// fade as LinearFieldSpec (w = radial_fade(|p − center|, radius, fade_width)). Purely
/// dissipative: F·v = −w B |v|² ≤ 0. No potential.
struct ViscousFieldSpec {
  double damping = 0.0;     // B. Unit: N·s/m. ≥ 0.
  Vec3 center_W;            // Unit: m. Used when radius > 0.
  double radius = 0.0;      // Unit: m. 0: everywhere; else > 0.
  double fade_width = 0.0;  // Unit: m. When radius > 0: 0 < fade_width ≤ radius.
};

FieldSample evaluate_field(const ViscousFieldSpec& spec, const Vec3& p_WT, const Vec3& v_WT);

// ---------------------------------------------------------------------------------------------
// Detent: a potential well with a repulsive rim (Russo L1050: "a strong potential well with a
// repulsive force around the periphery").

/// Over ρ = |f(p)| of a distance function (a point detent; a groove along a line or a plane; a
/// spherical shell), with s(t) = 3t² − 2t³:
///   U = −D + (D + H) s(ρ/R)          for ρ ≤ R       (the well, rising to the rim's crest)
///   U = H (1 − s((ρ − R)/w))         for R < ρ < R + w (the rim's outer slope)
///   U = 0                            for ρ ≥ R + w.
/// U is C¹ (dU/dρ = 0 at ρ = 0, R and R + w), so the force F = −U′(ρ) ∇ρ is continuous: inside R
/// it pulls toward the centre (near it a spring of stiffness 6(D + H)/R²), between R and R + w it
/// pushes outward (peak 1.5 H/w), beyond it is zero. Largest inward force 1.5 (D + H)/R at R/2.
struct DetentFieldSpec {
  DistanceSpec distance;    // Usually point_distance(centre).
  double depth = 0.0;       // D, U at the centre is −D. Unit: J. > 0.
  double radius = 0.0;      // R, radius of the rim's crest. Unit: m. > 0.
  double rim_height = 0.0;  // H, U on the crest. Unit: J. ≥ 0 (0: a plain well).
  double rim_width = 0.0;   // w, width of the rim's outer slope. Unit: m. > 0.
};

/// Always has_potential.
FieldSample evaluate_field(const DetentFieldSpec& spec, const Vec3& p_WT, const Vec3& v_WT);

/// The detent's profile U(ρ) and dU/dρ (J, J per unit of ρ) over any ρ ≥ 0 — a distance (m) here,
/// an angle (rad) for the orientation detent. depth, radius > 0; rim_width > 0 when rim_height > 0.
PotentialProfile detent_profile(double depth, double radius, double rim_height, double rim_width,
                                double rho);

// ---------------------------------------------------------------------------------------------
// Any field.

using EnergyFieldSpec = std::variant<PotentialFieldSpec, SpringFieldSpec, LinearFieldSpec,
                                     ViscousFieldSpec, DetentFieldSpec>;

/// Per-tick evaluation of a validated field. Does not allocate; never throws.
FieldSample evaluate_field(const EnergyFieldSpec& spec, const Vec3& p_WT, const Vec3& v_WT);

/// "" if usable, otherwise one message naming the bad parameter and its value, e.g.
/// "influence_distance: must be finite and > 0, got 0" or "distance.axis_W: must be finite and
/// non-zero, got (0, 0, 0)". Rejects NaN/inf everywhere and any parameter that would make the
/// force unbounded or non-finite where the field acts (Khatib without a positive min_distance,
/// n < 2, a zero-width fade). Off the loop (allocates the message).
std::string validate_field(const DistanceSpec& spec);
std::string validate_field(const PotentialFieldSpec& spec);
std::string validate_field(const SpringFieldSpec& spec);
std::string validate_field(const LinearFieldSpec& spec);
std::string validate_field(const ViscousFieldSpec& spec);
std::string validate_field(const DetentFieldSpec& spec);
std::string validate_field(const EnergyFieldSpec& spec);

// ---------------------------------------------------------------------------------------------
// Energy bookkeeping.

/// Work done by a field on the tool, W = ∫ F·v dt, by the trapezoidal rule between ticks:
/// W += ½ (P_prev + P) dt with P = F_T_W·v_WT (Unit: W). The first sample only records P.
/// work > 0: the field gave energy to the device (and the user); < 0: it absorbed energy.
/// For a conservative field W over a path equals U(start) − U(end). One meter per field (or
/// object); add() does not allocate.
struct EnergyMeter {
  double work = 0.0;           // Net work on the tool. Unit: J.
  double work_out = 0.0;       // Sum of the positive increments (energy given). Unit: J. ≥ 0.
  double work_in = 0.0;        // Minus the sum of the negative increments (absorbed). Unit: J. ≥ 0.
  double last_power = 0.0;     // P at the last sample. Unit: W.
  bool has_last = false;

  /// F_T_W: the field's force this tick (N); v_WT: tool velocity (m/s); dt: time since the
  /// previous sample (s), ignored on the first.
  void add(const Vec3& F_T_W, const Vec3& v_WT, double dt) { add_power(dot(F_T_W, v_WT), dt); }

  /// The same with the power P = F·v already formed. Unit: W.
  void add_power(double power, double dt) {
    if (has_last) {
      const double dW = 0.5 * (last_power + power) * dt;  // trapezoidal rule
      work += dW;
      if (dW > 0.0) {
        work_out += dW;
      } else {
        work_in -= dW;
      }
    }
    last_power = power;
    has_last = true;
  }
  void reset() { *this = EnergyMeter{}; }
};

}  // namespace haptic::engine
