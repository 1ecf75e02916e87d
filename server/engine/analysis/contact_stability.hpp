#pragma once
// Document 004's contact-instability model (Russo 1990, §4.2.2, L909–L955): the shaft axis as a
// motor-side mass M_m and a load-side mass M_s joined by the cable (k_t, b_t), the load side held
// by the hand (k_h, b_h). F_m is the force on the motor side, F_c the contact force on the hand,
// F_c = k_h x_s + b_h ẋ_s.
//   Eq. 4.4 (L932): F_c/F_m = [b_h b_t s² + (b_t k_h + b_h k_t) s + k_h k_t] /
//     [M_m M_s s⁴ + (b_t M_s + b_h M_m + b_t M_m) s³ + (k_t M_s + b_h b_t + k_t M_m + k_h M_m) s²
//      + (b_h k_t + b_t k_h) s + k_h k_t]
//   Eq. 4.5 (L937), the breakpoints: the roots ω² of the denominator's real part at s = jω,
//     ω²_{1,2} = a ∓ √(a² − k_h k_t / (M_m M_s)),  a = (k_t M_s + b_h b_t + M_m (k_t + k_h)) / (2 M_m M_s).
//   As printed the outer square root covers only a (ω = √a ± √(a² − …)), which is not
//   dimensionally consistent; the root must cover the whole of ω².
// Units: kg, N/m, N·s/m, rad/s.

#include <array>
#include <complex>
#include <string>

namespace haptic::engine {

struct ContactModelParams {
  double M_m = 0.30;      // Motor side: motor and brake rotors through r [I]. Unit: kg.
  double M_s = 0.11;      // Load side: shaft and load cell [I]. Unit: kg.
  double k_t = 82340.0;   // Cable stiffness (L935). Unit: N/m.
  double b_t = 45.0;      // Transmission damping (L935). Unit: N·s/m.
  double k_h = 700.0;     // Hand contact stiffness (L935). Unit: N/m.
  double b_h = 8.0;       // Hand contact damping (L935). Unit: N·s/m.

  /// Empty when usable; masses and k_t must be > 0, the rest ≥ 0, all finite.
  std::string validate() const;
};

/// Polynomial coefficients in s, highest power first.
struct ContactTransferFunction {
  std::array<double, 3> numerator{};    // s², s, 1
  std::array<double, 5> denominator{};  // s⁴, s³, s², s, 1
};

/// Eq. 4.4.
ContactTransferFunction contact_transfer_function(const ContactModelParams& p);
/// Eq. 4.3 (L922), the rigid transmission: F_c/F_m = (k_h + b_h s) / (M_s s² + b_h s + k_h),
/// with M_s here the whole moving mass.
ContactTransferFunction rigid_contact_transfer_function(const ContactModelParams& p);
/// F_c/F_m at complex frequency s. Unit: dimensionless.
std::complex<double> evaluate(const ContactTransferFunction& tf, std::complex<double> s);

/// Eq. 4.5 as corrected: ω1 < ω2. Unit: rad/s. NaN when the discriminant is negative.
struct ContactBreakpoints {
  double omega1 = 0.0;
  double omega2 = 0.0;
};
ContactBreakpoints contact_breakpoints(const ContactModelParams& p);

/// Where the force loop closed around eq. 4.4 with a proportional gain K goes unstable (L940–L946:
/// the root locus's higher, transmission pair crosses into the right half-plane, "ω_crit = 1200
/// rad/sec" with the document's masses): the frequency at which the loop's phase reaches −180°
/// and the gain K = 1 / |F_c/F_m| there. A load-cell filter 1 / (1 + s/ω_f) in the loop
/// (filter_cutoff = ω_f > 0; the document's is 130 Hz, L945) adds lag and lowers both.
/// Units: rad/s; the gain is dimensionless (force per force). NaN when the phase never reaches
/// −180° below 10⁶ rad/s.
struct CriticalForceGain {
  double omega = 0.0;
  double gain = 0.0;
};
CriticalForceGain critical_force_gain(const ContactModelParams& p, double filter_cutoff = 0.0);

}  // namespace haptic::engine
