#pragma once
// Natural frequencies of Madill 1998's flexible link 5 (§5.4.2, L2735–2836; Appendix B): an
// Euler–Bernoulli beam either clamped at one end and free at the other (eq. 5.10, from B.9), or
// carried by a hub of finite inertia with a point payload at the tip (Rossi's eq. 5.11).
// Off-line analysis: nothing here is used per tick. Units: SI (m, kg, N/m², rad/s).

namespace haptic::engine {

/// Second moment of area of a square tube of outer side h and wall d:
/// I = h⁴/12 − (h − 2d)⁴/12 (L2764). Unit: m⁴.
double square_tube_area_moment(double h, double d);
/// Cross-section of the same tube, A = h² − (h − 2d)² (L2768). Unit: m².
double square_tube_area(double h, double d);

/// A uniform beam.
struct BeamParams {
  double E = 69e9;        // Young's modulus (aluminium, L2770). Unit: N/m².
  double I = 1.28e-9;     // Second moment of area (L2764). Unit: m⁴.
  double rho_A = 2800.0 * 5.81e-5;  // Mass per length ρA (L2770, L2768). Unit: kg/m.
  double length = 0.433;  // Free length, not counting the clamp (L2722). Unit: m.
};

/// The k-th root (k ≥ 1) of the clamped-free characteristic equation cos(pl) cosh(pl) = −1
/// (B.9): 1.8751, 4.6941, 7.8548, … Solved by bisection on [(k−1)π, kπ] in the form
/// cos x + 1/cosh x = 0, which does not overflow.
double clamped_free_root(int k);

/// k-th natural frequency of the clamped-free beam, ω_k = (p_k l)² √(EI / (ρA l⁴)) (eq. 5.10
/// and the line before it). For §5.4's tube: ω_1 = 436 rad/s (69 Hz). Unit: rad/s.
double clamped_free_frequency(const BeamParams& beam, int k = 1);

/// The k-th clamped-free mode shape (B.8 with B.9's root p_k l), normalized so that
/// ∫₀ˡ φ_k² dx = 1 (L1102–1106): φ_k(x) = [cosh p x − cos p x − σ_k (sinh p x − sin p x)] / √l,
/// σ_k = (cosh p l + cos p l) / (sinh p l + sin p l), p = p_k. Signed so that φ_k''(0) > 0.
/// Meant for small k (the hyperbolic terms cancel in floating point as p x grows).
/// Units: x and length in m; φ in m^(−1/2).
double clamped_free_shape(int k, double x, double length);

/// φ_k(l), the normalized shape's value at the free end: 2 (−1)^(k+1) / √l (k = 1: 2.985 m^(−1/2)
/// for l = 0.449 m). Computed from clamped_free_shape. Unit: m^(−1/2).
double clamped_free_tip_value(int k, double length);

/// The modal participation of eqs. 3.29–3.31, β_k = ∫₀ˡ x φ_k dx. Since φ'''' = p⁴ φ and the free
/// end has φ''(l) = φ'''(l) = 0, integrating by parts twice gives β_k = φ_k''(0) / p_k⁴
/// = 2 l^(3/2) / (p_k l)² [derived here]; k = 1: 0.5688 l^(3/2). Unit: m^(3/2).
double clamped_free_participation(int k, double length);

/// Rossi's hub + beam + tip payload (eq. 5.11, L2800–2824).
struct HubPayloadBeamParams {
  double J0 = 0.677;   // Hub inertia of the base joint q0. Unit: kg·m².
  double M_p = 0.043;  // Payload (the axial load cell) at the tip. Unit: kg.
  double L = 0.449;    // Beam length. Unit: m.
  double rho = 0.163;  // Linear mass density. Unit: kg/m.
  double E = 69e9;     // Unit: N/m².
  double I = 1.28e-9;  // Unit: m⁴.
};

/// Left-hand side of eq. 5.11 at frequency ω, with β the fourth root of ρω²/(EI) (the thesis
/// prints β = ρω²/(EI), which is not dimensionally consistent with βL; the fourth root is the
/// usual wavenumber and reproduces the printed 223 rad/s), Ω0 = J0/ρ, Ω_p = M_p/ρ:
/// cos βL sinh βL − sin βL cosh βL − 2 Ω_p β sin βL sinh βL − Ω0 β³ (1 + cos βL cosh βL)
///   − β⁴ Ω_p Ω0 (cos βL sinh βL − sin βL cosh βL).
double hub_payload_characteristic(const HubPayloadBeamParams& beam, double omega);

/// The first positive root of eq. 5.11: a scan in βL from 0.05 in steps of 0.01, then
/// bisection to 1e-12 relative. For the thesis' values: 223 rad/s (35.5 Hz). Unit: rad/s.
/// Returns 0 when no root is found below βL = 20.
double hub_payload_first_frequency(const HubPayloadBeamParams& beam);

}  // namespace haptic::engine
