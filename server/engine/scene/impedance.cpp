#include "engine/scene/impedance.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include "engine/core/exact_zoh.hpp"

namespace haptic::engine {

ImpedanceDiscretization discretization_of(ContactLaw law) {
  switch (law) {
    case ContactLaw::kExactZoh: return ImpedanceDiscretization::kExactZoh;
    case ContactLaw::kTustin: return ImpedanceDiscretization::kTustin;
    default: return ImpedanceDiscretization::kBackwardDifference;
  }
}
namespace {

std::string format_value(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", value);
  return buffer;
}

/// "" if value is finite and >= 0, else "name: must be finite and >= 0, got value".
std::string check_non_negative(const char* name, double value) {
  if (std::isfinite(value) && value >= 0.0) return {};
  return std::string(name) + ": must be finite and >= 0, got " + format_value(value);
}

std::string check_finite(const char* name, const Vec3& v) {
  if (std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z)) return {};
  return std::string(name) + ": must be finite, got (" + format_value(v.x) + ", " +
         format_value(v.y) + ", " + format_value(v.z) + ")";
}

/// Spring-damper weights (c1, c2) of f = c1 d(k) + c2 d(k−1) for the backward and exact forms.
SpringDamperCoefficients spring_damper_weights(double K, double B, double T,
                                               ImpedanceDiscretization discretization) {
  // The exact form's limits are the backward ones: B → 0 gives a1 = K / (1 − e^{−∞}) = K, a2 = 0;
  // K → 0 gives a1 = −a2 = B/T (000 eq. 8.17: b_i is the first-order expansion of a_i, exact
  // for the pure spring and the pure damper, whose ZOH step is θ(k+1) = θ(k) + (T/B) τ(k)).
  if (discretization == ImpedanceDiscretization::kExactZoh && K > 0.0 && B > 0.0) {
    return exact_delayed_coefficients(K, B, T);  // 000 eq. 8.12
  }
  return euler_backward_coefficients(K, B, T);  // 000 eq. 8.16
}

// --- Polynomials (lowest power first) ---------------------------------------------------------

Polynomial make_polynomial(std::initializer_list<double> coefficients) {
  Polynomial p;
  int i = 0;
  for (double c : coefficients) p.c[static_cast<std::size_t>(i++)] = c;
  p.degree = std::max(0, i - 1);
  return p;
}

Polynomial multiply(const Polynomial& a, const Polynomial& b) {
  assert(a.degree + b.degree <= Polynomial::kMaxDegree);
  Polynomial r;
  r.degree = a.degree + b.degree;
  for (int i = 0; i <= a.degree; ++i) {
    for (int j = 0; j <= b.degree; ++j) {
      r.c[static_cast<std::size_t>(i + j)] +=
          a.c[static_cast<std::size_t>(i)] * b.c[static_cast<std::size_t>(j)];
    }
  }
  return r;
}

Polynomial add(const Polynomial& a, const Polynomial& b) {
  Polynomial r;
  r.degree = std::max(a.degree, b.degree);
  for (int i = 0; i <= r.degree; ++i) {
    const auto k = static_cast<std::size_t>(i);
    r.c[k] = (i <= a.degree ? a.c[k] : 0.0) + (i <= b.degree ? b.c[k] : 0.0);
  }
  return r;
}

/// Drops leading zero coefficients.
Polynomial trimmed(Polynomial p) {
  while (p.degree > 0 && p.c[static_cast<std::size_t>(p.degree)] == 0.0) --p.degree;
  return p;
}

/// The wall's transfer function W(z) = Nc(z) / Dc(z) from its filter weights (see
/// ImpedanceFilter): Σ lag[i] z^{−i} = (Σ lag[i] z^{L−i}) / z^L, and Tustin's velocity
/// V(z) = (2/T)(z − 1)/(z + 1) D(z).
void wall_transfer_function(const ImpedanceWeights& w, Polynomial& Nc, Polynomial& Dc) {
  int L = static_cast<int>(kImpedanceHistory);
  while (L > 0 && w.lag[static_cast<std::size_t>(L)] == 0.0) --L;
  Polynomial fir;
  fir.degree = L;
  for (int i = 0; i <= L; ++i) {
    fir.c[static_cast<std::size_t>(L - i)] = w.lag[static_cast<std::size_t>(i)];
  }
  Polynomial zL;
  zL.degree = L;
  zL.c[static_cast<std::size_t>(L)] = 1.0;
  if (w.velocity_gain == 0.0) {
    Nc = fir;
    Dc = zL;
    return;
  }
  const double g = w.velocity_gain * 2.0 / w.period;
  Nc = add(multiply(fir, make_polynomial({1.0, 1.0})), multiply(zL, make_polynomial({-g, g})));
  Dc = multiply(zL, make_polynomial({1.0, 1.0}));
}

std::complex<double> evaluate(const Polynomial& p, std::complex<double> z,
                              std::complex<double>* derivative) {
  std::complex<double> value = p.c[static_cast<std::size_t>(p.degree)];
  std::complex<double> slope = 0.0;
  for (int i = p.degree - 1; i >= 0; --i) {
    slope = slope * z + value;
    value = value * z + p.c[static_cast<std::size_t>(i)];
  }
  if (derivative != nullptr) *derivative = slope;
  return value;
}

}  // namespace

// --- The impedance law ------------------------------------------------------------------------

ImpedanceWeights impedance_weights(const ImpedanceParams& params,
                                   ImpedanceDiscretization discretization, double T) {
  assert(validate_impedance(params, T).empty());
  const double K = params.stiffness;
  const double B = params.damping;
  const double M = params.mass;
  const double m = M / (T * T);
  ImpedanceWeights w;
  w.period = T;
  switch (discretization) {
    case ImpedanceDiscretization::kBackwardDifference:
    case ImpedanceDiscretization::kExactZoh: {
      const SpringDamperCoefficients c = spring_damper_weights(K, B, T, discretization);
      // + M (d(k) − 2 d(k−1) + d(k−2)) / T²: the backward second difference (000 eq. 8.14
      // applied twice).
      w.lag = {c.c1 + m, c.c2 - 2.0 * m, m, 0.0};
      break;
    }
    case ImpedanceDiscretization::kTustin:
      // K d(k) + B v(k) with v the bilinear (trapezoidal) velocity, and the second-order
      // backward formula d̈(k) ≈ (2 d(k) − 5 d(k−1) + 4 d(k−2) − d(k−3)) / T², exact for cubics.
      w.lag = {K + 2.0 * m, -5.0 * m, 4.0 * m, -m};
      w.velocity_gain = B;
      break;
  }
  return w;
}

std::string validate_impedance(const ImpedanceParams& params, double T) {
  if (!(std::isfinite(T) && T > 0.0)) return "period: must be finite and > 0, got " + format_value(T);
  if (auto e = check_non_negative("stiffness", params.stiffness); !e.empty()) return e;
  if (auto e = check_non_negative("damping", params.damping); !e.empty()) return e;
  if (auto e = check_non_negative("mass", params.mass); !e.empty()) return e;
  return {};
}

void ImpedanceFilter::reset(double d_previous, double rate_previous,
                            double acceleration_previous) {
  const double T = weights_.period;
  for (std::size_t j = 0; j < kImpedanceHistory; ++j) {
    const double t = static_cast<double>(j) * T;
    history_[j] = d_previous - t * rate_previous + 0.5 * t * t * acceleration_previous;
  }
  velocity_ = rate_previous;
}

// --- Polynomials, roots, Jury -----------------------------------------------------------------

std::array<std::complex<double>, Polynomial::kMaxDegree> polynomial_roots(const Polynomial& input) {
  std::array<std::complex<double>, Polynomial::kMaxDegree> roots{};
  Polynomial p = trimmed(input);
  assert(p.degree >= 1);
  // Roots at zero come off exactly.
  int found = 0;
  while (p.degree > 0 && p.c[0] == 0.0) {
    for (int i = 0; i < p.degree; ++i) {
      p.c[static_cast<std::size_t>(i)] = p.c[static_cast<std::size_t>(i + 1)];
    }
    p.c[static_cast<std::size_t>(p.degree)] = 0.0;
    --p.degree;
    roots[static_cast<std::size_t>(found++)] = 0.0;
  }
  const int n = p.degree;
  if (n == 0) return roots;
  // Starting points on a circle of the geometric-mean root radius, off the real axis
  // (Aberth 1973; the rotation 0.4 keeps them off symmetric root sets).
  const double radius = std::pow(std::abs(p.c[0] / p.c[static_cast<std::size_t>(n)]), 1.0 / n);
  std::array<std::complex<double>, Polynomial::kMaxDegree> z{};
  for (int i = 0; i < n; ++i) {
    const double angle = 2.0 * std::numbers::pi * i / n + 0.4;
    z[static_cast<std::size_t>(i)] = std::polar(radius, angle);
  }
  // Aberth–Ehrlich: z_i ← z_i − w_i / (1 − w_i Σ_{j≠i} 1/(z_i − z_j)), w_i = p(z_i)/p'(z_i).
  for (int iteration = 0; iteration < 500; ++iteration) {
    double largest_step = 0.0;
    for (int i = 0; i < n; ++i) {
      auto& zi = z[static_cast<std::size_t>(i)];
      std::complex<double> derivative;
      const std::complex<double> value = evaluate(p, zi, &derivative);
      if (value == 0.0) continue;
      const std::complex<double> w = value / derivative;
      std::complex<double> sum = 0.0;
      for (int j = 0; j < n; ++j) {
        if (j != i) sum += 1.0 / (zi - z[static_cast<std::size_t>(j)]);
      }
      const std::complex<double> step = w / (1.0 - w * sum);
      if (std::isfinite(step.real()) && std::isfinite(step.imag())) {
        zi -= step;
        largest_step = std::max(largest_step, std::abs(step) / std::max(1.0, std::abs(zi)));
      }
    }
    if (largest_step < 1e-15) break;
  }
  // Two Newton steps each, kept only where they reduce |p|.
  for (int i = 0; i < n; ++i) {
    auto& zi = z[static_cast<std::size_t>(i)];
    for (int k = 0; k < 2; ++k) {
      std::complex<double> derivative;
      const std::complex<double> value = evaluate(p, zi, &derivative);
      if (derivative == 0.0) break;
      const std::complex<double> candidate = zi - value / derivative;
      if (std::abs(evaluate(p, candidate, nullptr)) < std::abs(value)) zi = candidate;
    }
    roots[static_cast<std::size_t>(found++)] = zi;
  }
  return roots;
}

bool schur_stable(const Polynomial& input) {
  Polynomial p = trimmed(input);
  std::array<double, Polynomial::kMaxDegree + 1> a = p.c;
  int n = p.degree;
  // Schur–Cohn reduction (Jury 1964): with a_0 … a_n the coefficients, every root lies inside the
  // unit circle iff |a_0| < |a_n| and the degree n−1 polynomial
  // (a_n p(z) − a_0 z^n p(1/z)) / z, of coefficients a_n a_{i+1} − a_0 a_{n−1−i}, has the same
  // property.
  while (n > 0) {
    if (!(std::abs(a[0]) < std::abs(a[static_cast<std::size_t>(n)]))) return false;
    std::array<double, Polynomial::kMaxDegree + 1> b{};
    double scale = 0.0;
    for (int i = 0; i < n; ++i) {
      b[static_cast<std::size_t>(i)] = a[static_cast<std::size_t>(n)] * a[static_cast<std::size_t>(i + 1)] -
                                       a[0] * a[static_cast<std::size_t>(n - 1 - i)];
      scale = std::max(scale, std::abs(b[static_cast<std::size_t>(i)]));
    }
    if (!(scale > 0.0) || !std::isfinite(scale)) return false;
    for (int i = 0; i < n; ++i) b[static_cast<std::size_t>(i)] /= scale;  // no over/underflow
    a = b;
    --n;
  }
  return true;
}

// --- Sampled wall -----------------------------------------------------------------------------

namespace {

/// X(z)/F(z) = N/D of the device with an actuator lag τ_a > 0, sampled with a ZOH over T: the
/// states (x, v, f), A = [[0, 1, 0], [0, −b/m, 1/m], [0, 0, −1/τ_a]], B = (0, 0, 1/τ_a), C = (1,
/// 0, 0); e^{[[A, B], [0, 0]] T} = [[Φ, Γ], [0, 1]]. With t = tr Φ and c the sum of Φ's principal
/// 2×2 minors: D = z³ − t z² + c z − det Φ, and adj(zI − Φ) = z² I + z (Φ − t I) + Φ² − t Φ + c I.
void lagged_device(const MassDamperDevice& device, double T, Polynomial& N, Polynomial& D) {
  const std::array<std::array<double, 3>, 3> a = {{{0.0, 1.0, 0.0},
                                                   {0.0, -device.damping / device.mass, 1.0 / device.mass},
                                                   {0.0, 0.0, -1.0 / device.actuator_lag}}};
  const ZohStep<3> step = exact_zoh<3>(a, {0.0, 0.0, 1.0 / device.actuator_lag}, T);
  const auto phi = [&](std::size_t i, std::size_t j) { return step.phi[i][j]; };
  const std::array<double, 3>& gamma = step.gamma;
  const double trace = phi(0, 0) + phi(1, 1) + phi(2, 2);
  const auto minor = [&](std::size_t i, std::size_t j) { return phi(i, i) * phi(j, j) - phi(i, j) * phi(j, i); };
  const double minors = minor(0, 1) + minor(0, 2) + minor(1, 2);
  const double det = phi(0, 0) * minor(1, 2) - phi(0, 1) * (phi(1, 0) * phi(2, 2) - phi(1, 2) * phi(2, 0)) +
                     phi(0, 2) * (phi(1, 0) * phi(2, 1) - phi(1, 1) * phi(2, 0));
  // C M Γ is row 0 of M times Γ.
  const auto first_row_times_gamma = [&](const auto& row) { return row(0) * gamma[0] + row(1) * gamma[1] + row(2) * gamma[2]; };
  const double n2 = gamma[0];
  const double n1 = first_row_times_gamma([&](std::size_t j) { return phi(0, j) - (j == 0 ? trace : 0.0); });
  const double n0 = first_row_times_gamma([&](std::size_t j) {
    double square = 0.0;
    for (std::size_t k = 0; k < 3; ++k) square += phi(0, k) * phi(k, j);
    return square - trace * phi(0, j) + (j == 0 ? minors : 0.0);
  });
  N = make_polynomial({n0, n1, n2});
  D = make_polynomial({-det, minors, -trace, 1.0});
}

}  // namespace

Polynomial wall_characteristic_polynomial(const ImpedanceWeights& wall,
                                          const MassDamperDevice& device, double delay_ticks) {
  const double T = wall.period;
  const double m = device.mass;
  const double x = device.damping * T / m;
  // The device's exact ZOH step, as engine/device/point_mass_plant.cpp: e = e^{−x},
  // φ = (1 − e)/x, g = (x − 1 + e)/x² (series below x = 0.1: the direct form cancels).
  double e = 1.0, phi = 1.0, g = 0.5;
  if (x > 0.0) {
    const double em1 = std::expm1(-x);
    e = 1.0 + em1;
    phi = -em1 / x;
    if (x < 0.1) {
      double term = 0.5, sum = 0.5;
      for (int n = 1; n < 12; ++n) {
        term *= -x / static_cast<double>(n + 2);
        sum += term;
      }
      g = sum;
    } else {
      g = (x + em1) / (x * x);
    }
  }
  // x(k+1) = x(k) + T φ v(k) + (T²/m) g F(k), v(k+1) = e v(k) + (T/m) φ F(k), so
  // X(z)/F(z) = (T²/m)(g z + φ² − e g) / ((z − 1)(z − e)).
  Polynomial N, D;
  if (device.actuator_lag > 0.0) {
    lagged_device(device, T, N, D);
  } else {
    N = make_polynomial({T * T / m * (phi * phi - e * g), T * T / m * g});
    D = make_polynomial({e, -(1.0 + e), 1.0});
  }
  Polynomial Nc, Dc;
  wall_transfer_function(wall, Nc, Dc);
  // The delay: z^d on the wall's denominator side (F(z) = −z^{−d} W(z) X(z)). A fractional one,
  // d = n + f, as n ticks and Thiran's first-order all-pass for the rest (Laakso et al. 1996,
  // "Splitting the unit delay", §III.B): A(z) = (η + z^{−1}) / (1 + η z^{−1}), η = (1 − f)/(1 + f),
  // whose magnitude is 1 and whose delay is f at low frequencies; so
  // z^n (z + η) D Dc + (η z + 1) N Nc = 0.
  const double clamped = std::clamp(delay_ticks, 0.0, static_cast<double>(Polynomial::kMaxDelayTicks - 1));
  const int n = static_cast<int>(std::floor(clamped));
  const double f = clamped - static_cast<double>(n);
  Polynomial delay;
  if (f < 1e-12) {
    delay.degree = n;
    delay.c[static_cast<std::size_t>(n)] = 1.0;
    return trimmed(add(multiply(multiply(D, Dc), delay), multiply(N, Nc)));
  }
  const double eta = (1.0 - f) / (1.0 + f);
  delay.degree = n;
  delay.c[static_cast<std::size_t>(n)] = 1.0;
  const Polynomial denominator = make_polynomial({eta, 1.0});  // z + η
  const Polynomial numerator = make_polynomial({1.0, eta});    // η z + 1
  return trimmed(add(multiply(multiply(multiply(D, Dc), delay), denominator), multiply(multiply(numerator, N), Nc)));
}

namespace {

double max_root_magnitude(const Polynomial& p) {
  const auto roots = polynomial_roots(p);
  double largest = 0.0;
  for (int i = 0; i < p.degree; ++i) {
    largest = std::max(largest, std::abs(roots[static_cast<std::size_t>(i)]));
  }
  return largest;
}

bool wall_stable(ImpedanceParams wall, double K, ImpedanceDiscretization discretization,
                 const MassDamperDevice& device, double T, double delay_ticks) {
  wall.stiffness = K;
  return schur_stable(
      wall_characteristic_polynomial(impedance_weights(wall, discretization, T), device, delay_ticks));
}

}  // namespace

SampledWallMargin sampled_wall_margin(const ImpedanceParams& wall,
                                      ImpedanceDiscretization discretization,
                                      const MassDamperDevice& device, double T,
                                      double delay_ticks) {
  SampledWallMargin margin;
  const Polynomial p = wall_characteristic_polynomial(impedance_weights(wall, discretization, T),
                                                      device, delay_ticks);
  margin.max_pole_magnitude = max_root_magnitude(p);
  margin.stable = schur_stable(p);
  margin.colgate_damping = colgate_bound(wall.stiffness, wall.damping, T);
  margin.passive = device.damping > margin.colgate_damping;

  // Scan up from far below the device's own stiffness scale m/T² for the first stable K', then
  // double to the first unstable one and bisect between them.
  const double scale = device.mass / (T * T);
  double lo = 0.0;
  for (double K = 1e-12 * scale; K <= 1e12; K *= 10.0) {
    if (wall_stable(wall, K, discretization, device, T, delay_ticks)) {
      lo = K;
      break;
    }
  }
  if (lo == 0.0) {
    margin.max_stable_stiffness = 0.0;
    return margin;
  }
  double hi = lo;
  while (wall_stable(wall, hi, discretization, device, T, delay_ticks)) {
    lo = hi;
    hi *= 2.0;
    if (hi > 1e12) {
      margin.max_stable_stiffness = std::numeric_limits<double>::infinity();
      return margin;
    }
  }
  while (hi - lo > 1e-9 * hi) {
    const double mid = 0.5 * (lo + hi);
    (wall_stable(wall, mid, discretization, device, T, delay_ticks) ? lo : hi) = mid;
  }
  margin.max_stable_stiffness = lo;
  return margin;
}

// --- Virtual coupling -------------------------------------------------------------------------

VirtualCouplingDesign design_virtual_coupling(double m, double b, double T, double damping_share,
                                              double margin) {
  VirtualCouplingDesign design;
  if (!(m > 0.0 && b > 0.0 && T > 0.0 && std::isfinite(m) && std::isfinite(b) &&
        std::isfinite(T))) {
    return design;
  }
  damping_share = std::clamp(damping_share, 0.0, 1.0);
  margin = std::clamp(margin, 0.0, 1.0);
  design.gains.damping = damping_share * b;
  // Madill eq. 2.6 solved for K: b > K T/2 + B_c  ⇔  K < 2 (b − B_c)/T.
  design.gains.stiffness = margin * 2.0 * (b - design.gains.damping) / T;
  design.natural_frequency = std::sqrt(design.gains.stiffness / m);
  design.damping_ratio = design.gains.stiffness > 0.0
                             ? (b + design.gains.damping) / (2.0 * std::sqrt(design.gains.stiffness * m))
                             : std::numeric_limits<double>::infinity();
  return design;
}

// --- Tangent plane ----------------------------------------------------------------------------

std::string validate_tangent_plane(const TangentPlane& plane, double T) {
  if (auto e = check_finite("point", plane.point_W); !e.empty()) return e;
  if (auto e = check_finite("normal", plane.normal_W); !e.empty()) return e;
  if (auto e = check_finite("reference", plane.reference_W); !e.empty()) return e;
  const double length = norm(plane.normal_W);
  if (std::abs(length - 1.0) > 1e-6) {
    return "normal: must be a unit vector, got length " + format_value(length);
  }
  if (auto e = validate_impedance(plane.normal, T); !e.empty()) return "normal_impedance." + e;
  if (auto e = check_non_negative("tangential_stiffness", plane.tangential_stiffness); !e.empty()) {
    return e;
  }
  return check_non_negative("tangential_damping", plane.tangential_damping);
}

void TangentPlaneContact::set_plane(const TangentPlane& plane) {
  plane_ = plane;
  normal_filter_ = ImpedanceFilter(plane.normal, discretization_, period_);
  has_plane_ = true;
  plane_changed_ = true;
}

TangentPlaneForce TangentPlaneContact::update(const Vec3& p_WT, const Vec3& v_WT) {
  TangentPlaneForce out;
  if (!has_plane_) return out;
  const Vec3& n = plane_.normal_W;
  const double d = dot(plane_.point_W - p_WT, n);
  const double rate = -dot(v_WT, n);  // ḋ from the measured velocity
  out.penetration = d;
  if (d > 0.0) {
    // A new contact, or a new plane (and weights) during one: seed the filter with the previous
    // sample's penetration under the current plane and the measured rate.
    if (!in_contact_ || plane_changed_) {
      const double d_previous =
          has_previous_ ? dot(plane_.point_W - p_previous_W_, n) : d - period_ * rate;
      normal_filter_.reset(d_previous, rate, 0.0);
    }
    in_contact_ = true;
    out.in_contact = true;
    // Russo ch. 5: the normal impedance only repels.
    const double f_n = std::max(0.0, normal_filter_.update(d));
    const Vec3 e = p_WT - plane_.reference_W;
    const Vec3 e_t = e - dot(e, n) * n;
    const Vec3 v_t = v_WT - dot(v_WT, n) * n;
    out.F_T_W = f_n * n - plane_.tangential_stiffness * e_t - plane_.tangential_damping * v_t;
  } else {
    in_contact_ = false;
  }
  plane_changed_ = false;
  p_previous_W_ = p_WT;
  has_previous_ = true;
  return out;
}

}  // namespace haptic::engine
