#include "engine/analysis/contact_stability.hpp"

#include <cmath>
#include <limits>
#include <sstream>

namespace haptic::engine {

std::string ContactModelParams::validate() const {
  const auto check = [](const char* name, double v, bool strictly) -> std::string {
    if (std::isfinite(v) && (strictly ? v > 0.0 : v >= 0.0)) return {};
    std::ostringstream out;
    out << name << ": must be finite and " << (strictly ? "> 0" : ">= 0") << ", got " << v;
    return out.str();
  };
  for (const std::string& message :
       {check("M_m", M_m, true), check("M_s", M_s, true), check("k_t", k_t, true),
        check("b_t", b_t, false), check("k_h", k_h, false), check("b_h", b_h, false)}) {
    if (!message.empty()) return message;
  }
  return {};
}

ContactTransferFunction contact_transfer_function(const ContactModelParams& p) {
  ContactTransferFunction tf;
  tf.numerator = {p.b_h * p.b_t, p.b_t * p.k_h + p.b_h * p.k_t, p.k_h * p.k_t};
  tf.denominator = {p.M_m * p.M_s,
                    p.b_t * p.M_s + p.b_h * p.M_m + p.b_t * p.M_m,
                    p.k_t * p.M_s + p.b_h * p.b_t + p.k_t * p.M_m + p.k_h * p.M_m,
                    p.b_h * p.k_t + p.b_t * p.k_h,
                    p.k_h * p.k_t};
  return tf;
}

ContactTransferFunction rigid_contact_transfer_function(const ContactModelParams& p) {
  ContactTransferFunction tf;
  tf.numerator = {0.0, p.b_h, p.k_h};
  tf.denominator = {0.0, 0.0, p.M_s, p.b_h, p.k_h};
  return tf;
}

std::complex<double> evaluate(const ContactTransferFunction& tf, std::complex<double> s) {
  std::complex<double> num = 0.0, den = 0.0;
  for (const double c : tf.numerator) num = num * s + c;    // Horner
  for (const double c : tf.denominator) den = den * s + c;
  return num / den;
}

ContactBreakpoints contact_breakpoints(const ContactModelParams& p) {
  const double mm = p.M_m * p.M_s;
  const double a = (p.k_t * p.M_s + p.b_h * p.b_t + p.M_m * (p.k_t + p.k_h)) / (2.0 * mm);
  const double discriminant = a * a - p.k_h * p.k_t / mm;
  if (!(discriminant >= 0.0)) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan};
  }
  const double root = std::sqrt(discriminant);
  // ω1² = a − √(…) loses digits to cancellation; use the product of the roots instead.
  const double w2_sq = a + root;
  const double w1_sq = (p.k_h * p.k_t / mm) / w2_sq;
  return {std::sqrt(w1_sq), std::sqrt(w2_sq)};
}

CriticalForceGain critical_force_gain(const ContactModelParams& p, double filter_cutoff) {
  const ContactTransferFunction tf = contact_transfer_function(p);
  const auto loop = [&](double omega) {
    const std::complex<double> s(0.0, omega);
    const std::complex<double> filter = filter_cutoff > 0.0 ? 1.0 / (1.0 + s / filter_cutoff) : 1.0;
    return evaluate(tf, s) * filter;
  };
  // The phase falls through −180° where the imaginary part changes sign with the real part < 0:
  // scanned at 1 % steps from 1 rad/s, then bisected to 1e-12 relative.
  double lo = 1.0;
  for (double hi = lo * 1.01; hi < 1e6; lo = hi, hi *= 1.01) {
    const std::complex<double> a = loop(lo), b = loop(hi);
    if (b.real() < 0.0 && (a.imag() < 0.0) != (b.imag() < 0.0)) {
      while (hi - lo > 1e-12 * hi) {
        const double mid = 0.5 * (lo + hi);
        ((loop(mid).imag() < 0.0) == (a.imag() < 0.0) ? lo : hi) = mid;
      }
      return {lo, 1.0 / std::abs(loop(lo))};
    }
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  return {nan, nan};
}

}  // namespace haptic::engine
