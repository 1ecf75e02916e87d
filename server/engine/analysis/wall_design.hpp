#pragma once
// Frequency-domain design of the velocity gain of a virtual-wall controller for one axis
// (Eom, Suh, Yi, "A Design Method of Haptic Interface Controller Considering Transparency and
// Robust Stability", eqs. 6–17, Figs. 3, 5, 8). Pure computation, off the loop: it chooses a gain
// that the loop then uses.
//
//   P(s)   = 1 / (m s + b)                       device with a disturbance observer   (eq. 7)
//   V(s)   = (K + B s) / s                       virtual wall, velocity -> force       (eq. 8)
//   Y_v(s) = 1 / V(s) = s / (K + B s)            admittance of the wall                (eq. 11)
//   C(s)   = B_c + K_c / s,  K_c = K             feedback controller                   (eq. 12)
//   Y_t(s) = P / (1 + ZOH P C)                   transmitted admittance                (eq. 9)
//   J      = ||w1 (Y_v − Y_t)||_2^2              transparency index                    (eq. 11)
//   W(s)   = α m s + β b                         parametric uncertainty weight         (eq. 15)
//   L(s)   = −W P / (1 + ZOH P C)                robustly stable iff ||L||_∞ <= 1      (eqs. 16, 17)
//
// The document approximates the zero-order hold by "a low pass filter with unity steady-state gain
// and 90 degrees phase lag at the Nyquist frequency" without giving it. The default here
//   ZOH(s) = ω_N² / (s² + 2 ζ ω_N s + ω_N²),   ω_N = π / T,  ζ = π / 4:
// unity gain at DC and exactly −90° at ω_N by construction; ζ = π/4 makes its low-frequency phase
// −ωT/2 (the exact hold's, (1 − e^{−sT}) / (sT)) and its gain at ω_N 1/(2ζ) = 2/π (also the
// exact hold's). A first-order 1/(1 + sT/2) would reach only −57.5° at ω_N. Near the optimum the
// robust-stability verdict depends on this choice (‖L‖∞ from −0.7 to +1.0 dB on the document's
// device), so the other usual models of the hold are here too (HoldModel) and haptic-lab reports
// each one's verdict.
//
// w1, which the document leaves open ("a low pass filter", eq. 11), is w1(s) = ω_1 / (s + ω_1);
// the default ω_1 = 100 rad/s (about 16 Hz, the band of a hand's voluntary force) puts the optimum
// near the document's B_c = 15 N*s/m (Fig. 8). The optimum rises with ω_1.

#include <complex>

namespace haptic::engine {

/// How the loop's hold and sampling delay enter the continuous-time design (the ZOH(s) of eq. 9).
enum class HoldModel {
  kSecondOrder,  // ω_N² / (s² + 2ζω_N s + ω_N²), ζ = π/4 (above): the document's description
  kHalfPeriodDelay,  // e^{−sT/2}: the hold's average delay, with no roll-off
  kPade,         // (1 − sT/4) / (1 + sT/4): first-order Padé of e^{−sT/2}, an all-pass
  kExact,        // (1 − e^{−sT}) / (sT): the hold's own frequency response (delay and sinc roll-off)
};

/// Every hold model, in the order haptic-lab reports them.
inline constexpr HoldModel kHoldModels[] = {HoldModel::kSecondOrder, HoldModel::kHalfPeriodDelay,
                                            HoldModel::kPade, HoldModel::kExact};

/// "second-order", "delay", "pade", "exact": the names haptic-lab's --hold takes.
const char* hold_model_name(HoldModel hold);

/// One axis of the haptic loop of Eom et al. Fig. 3; defaults are their experiment's values.
struct WallDesignParams {
  double mass = 0.01;              // m. Unit: kg. > 0.
  double damping = 0.022;          // b. Unit: N*s/m. >= 0.
  double wall_stiffness = 1000.0;  // K (and K_c). Unit: N/m. > 0.
  double wall_damping = 1.0;       // B. Unit: N*s/m. > 0.
  double sample_period = 0.001;    // T. Unit: s. > 0.
  double weight_cutoff = 100.0;    // ω_1 of w1 (about 16 Hz). Unit: rad/s. > 0.
  double mass_uncertainty = 0.5;     // α of eq. 13, in [0, 1).
  double damping_uncertainty = 0.5;  // β of eq. 13, in [0, 1).
  HoldModel hold = HoldModel::kSecondOrder;  // ZOH(s) of eq. 9
};

using Complex = std::complex<double>;

/// P(s) = 1/(ms + b) (eq. 7). Unit: m/(N*s).
Complex device_admittance(const WallDesignParams& p, Complex s);
/// ZOH(s) of eq. 9 as p.hold models it (dimensionless). |ZOH(jω)| <= 1 for every model.
Complex hold_response(const WallDesignParams& p, Complex s);
/// V(s) = (K + Bs)/s (eq. 8). Unit: N*s/m.
Complex virtual_wall(const WallDesignParams& p, Complex s);
/// Y_v(s) = 1/V(s) (eq. 11). Unit: m/(N*s).
Complex wall_admittance(const WallDesignParams& p, Complex s);
/// C(s) = B_c + K/s (eq. 12 with K_c = K). controller_damping = B_c, Unit: N*s/m.
Complex controller(const WallDesignParams& p, double controller_damping, Complex s);
/// Y_t(s) = P/(1 + ZOH P C) (eq. 9). Unit: m/(N*s).
Complex transmitted_admittance(const WallDesignParams& p, double controller_damping, Complex s);
/// w1(s) = ω_1/(s + ω_1) (dimensionless).
Complex transparency_weight(const WallDesignParams& p, Complex s);
/// L(s) = −W P/(1 + ZOH P C), W = α m s + β b (eqs. 15, 16; dimensionless).
Complex uncertainty_loop(const WallDesignParams& p, double controller_damping, Complex s);

/// Whether the nominal loop 1 + ZOH P C = 0 has all its roots in the open left half-plane. J and
/// ||L||_∞ only mean what eqs. 11 and 17 say for a stable nominal loop. For the rational holds,
/// Routh–Hurwitz on the characteristic polynomial (a quartic for kSecondOrder, a cubic for kPade);
/// for kHalfPeriodDelay and kExact, whose characteristic function is not a polynomial,
/// right_half_plane_roots() == 0.
bool nominal_loop_stable(const WallDesignParams& p, double controller_damping);

/// The number of roots of s (m s + b) + ZOH(s) (B_c s + K), the nominal loop's characteristic
/// function, with Re s >= 0, by the argument principle: its phase is followed along s = jω from
/// ω = 0 (where it is K > 0) until m ω² > B_c ω + K, beyond which the m s² term outweighs the rest
/// (|ZOH| <= 1) and the remaining phase is known in closed form. Valid for every hold model (each
/// ZOH(s) is analytic in the right half-plane); the phase is sampled finely enough to follow
/// e^{−jωT}. Always even (f(0) > 0 and f → +∞ along the positive real axis).
int right_half_plane_roots(const WallDesignParams& p, double controller_damping);

/// J(B_c) of eq. 11, (1/π) ∫_0^∞ |w1 (Y_v − Y_t)|² dω (the integrand is even in ω): trapezoids in
/// ln ω, 400 points per decade from 1e-2 rad/s to 1000 ω_N, plus the tail above,
/// ω_1² / (B² ω_max), in closed form (there Y_t ≈ 0, Y_v ≈ 1/B, |w1| ≈ ω_1/ω).
/// Unit: m²/(N²*s) (the integral of a squared velocity per unit force impulse, eq. 10).
double transparency_index(const WallDesignParams& p, double controller_damping);

/// ||L||_∞ (eq. 17) over 0.1 rad/s … ω_N = π/T: the largest |L(jω)| on a grid of 2000 points per
/// decade, refined by golden-section search between the neighbours of the largest sample.
/// Dimensionless (linear, not dB).
double robust_stability_norm(const WallDesignParams& p, double controller_damping);

/// 20 log10(gain).
double to_db(double gain);

struct OptimalWallDesign {
  double controller_damping = 0.0;  // B_c minimising J. Unit: N*s/m.
  double transparency_index = 0.0;  // J there (eq. 11).
  double robust_stability_norm = 0.0;  // ||L||_∞ there (eq. 17), linear.
  bool nominal_loop_stable = false;
  bool robustly_stable = false;  // nominal_loop_stable and ||L||_∞ <= 1 (Eom et al. Theorem 1).
};

/// The B_c in [lo, hi] minimising J (the first step of the "numerical recursive method" after
/// eq. 17), then checked against eq. 17. J is scanned at 61 points evenly spaced in ln B_c, and
/// golden-section search on ln B_c refines the bracket around the smallest sample to 1e-6
/// relative. Unit of lo, hi: N*s/m; 0 < lo < hi.
OptimalWallDesign optimise_controller_damping(const WallDesignParams& p, double lo = 0.1,
                                              double hi = 100.0);

}  // namespace haptic::engine
