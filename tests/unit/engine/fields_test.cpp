// Energy fields (Russo 1990 ch. 5): distance functions, polynomial and Khatib potentials, springs,
// the first-order field, the viscous field, the detent, validation and the energy meter.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "engine/scene/fields.hpp"
#include "support/allocation_counter.hpp"

namespace haptic::engine {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

double distance_between(const Vec3& a, const Vec3& b) { return norm(a - b); }

// Ratios err(h)/err(h/2) and err(h/2)/err(h/4) of an O(h²) method are ≈ 4.
void ExpectSecondOrder(const std::vector<double>& errors, const char* what) {
  ASSERT_EQ(errors.size(), 3u);
  for (std::size_t i = 0; i + 1 < errors.size(); ++i) {
    ASSERT_GT(errors[i + 1], 0.0) << what;
    const double ratio = errors[i] / errors[i + 1];
    EXPECT_GT(ratio, 3.7) << what << " ratio " << ratio;
    EXPECT_LT(ratio, 4.3) << what << " ratio " << ratio;
  }
}

// ---- distance functions ----------------------------------------------------------------------

TEST(Fields, DistanceFunctionsGiveTheirDefiningValues) {
  EXPECT_DOUBLE_EQ(evaluate_distance(point_distance({1, 2, 3}), {1, 2, 7}).f, 4.0);
  EXPECT_DOUBLE_EQ(evaluate_distance(line_distance({0, 0, 0}, {0, 0, 5}), {3, 4, 9}).f, 5.0);
  const DistanceSample plane = evaluate_distance(plane_distance({0, 0, 1}, {0, 0, 2}), {5, 5, -2});
  EXPECT_DOUBLE_EQ(plane.f, -3.0);  // signed: below the plane
  EXPECT_EQ(plane.grad_f, (Vec3{0, 0, 1}));
  const DistanceSample inside = evaluate_distance(sphere_distance({0, 0, 0}, 0.5), {0.3, 0, 0});
  EXPECT_DOUBLE_EQ(inside.f, -0.2);  // signed: inside the sphere
  EXPECT_EQ(inside.grad_f, (Vec3{1, 0, 0}));
}

TEST(Fields, DistanceGradientsMatchCentralDifferencesToSecondOrder) {
  const Vec3 p{0.031, -0.017, 0.012};
  const DistanceSpec curved[] = {point_distance({0.005, 0.01, -0.002}),
                                 line_distance({0.002, -0.004, 0.0}, {1.0, 2.0, 0.5}),
                                 sphere_distance({-0.004, 0.003, 0.001}, 0.02)};
  for (const DistanceSpec& d : curved) {
    const auto f = [&d](const Vec3& q) { return evaluate_distance(d, q).f; };
    const Vec3 analytic = evaluate_distance(d, p).grad_f;
    std::vector<double> errors;
    for (double h : {2e-3, 1e-3, 5e-4}) {
      errors.push_back(distance_between(central_difference_gradient(f, p, h), analytic));
    }
    ExpectSecondOrder(errors, "distance gradient");
  }
  // f is linear for a plane: central differences are exact up to rounding.
  const DistanceSpec plane = plane_distance({0.01, 0.0, 0.0}, {0.3, -0.4, 1.2});
  const auto f = [&plane](const Vec3& q) { return evaluate_distance(plane, q).f; };
  EXPECT_LT(distance_between(central_difference_gradient(f, p, 1e-3),
                             evaluate_distance(plane, p).grad_f),
            1e-12);
}

// ---- potentials (eqs. 5.6, 5.7) --------------------------------------------------------------

PotentialFieldSpec polynomial(DistanceSpec d, int n, double K, double c) {
  return {.distance = d, .kind = PotentialKind::kPolynomial, .order = n, .gain = K, .offset = c};
}

PotentialFieldSpec khatib(DistanceSpec d, int n, double K, double f0, double fm) {
  return {.distance = d,
          .kind = PotentialKind::kKhatib,
          .order = n,
          .gain = K,
          .influence_distance = f0,
          .min_distance = fm};
}

TEST(Fields, PotentialGradientsEq56And57MatchCentralDifferencesToSecondOrder) {
  struct Case {
    PotentialFieldSpec spec;
    Vec3 p;
  };
  const Case cases[] = {
      // Polynomial (eq. 5.6): a solid ball around a point, a cylinder around a line, a half-space
      // below a plane, a sphere; orders 2 to 4.
      {polynomial(point_distance({0, 0, 0}), 2, 2000.0, 0.05), {0.02, -0.015, 0.01}},
      {polynomial(line_distance({0, 0, 0}, {0, 1, 1}), 3, 8e4, 0.05), {0.02, 0.01, -0.015}},
      {polynomial(plane_distance({0, 0, 0}, {0, 0, 1}), 3, 1e5, 0.0), {0.01, 0.02, -0.02}},
      {polynomial(plane_distance({0, 0, 0}, {1, 1, 0}), 4, 1e7, 0.0), {-0.02, 0.005, 0.0}},
      {polynomial(sphere_distance({0, 0, 0}, 0.04), 2, 1500.0, 0.0), {0.015, 0.015, -0.01}},
      // Khatib (eq. 5.7) outside a plane, a sphere and a point.
      {khatib(plane_distance({0, 0, 0}, {0, 0, 1}), 2, 1e-6, 0.05, 1e-3), {0.0, 0.0, 0.02}},
      {khatib(sphere_distance({0, 0, 0}, 0.03), 2, 1e-6, 0.04, 1e-3), {0.03, 0.02, 0.01}},
      {khatib(point_distance({0, 0, 0}), 3, 1e-5, 0.06, 1e-3), {0.02, -0.01, 0.015}},
  };
  for (const Case& c : cases) {
    ASSERT_EQ(validate_field(c.spec), "");
    const Vec3 analytic = evaluate_field(c.spec, c.p, {}).F_T_W;
    ASSERT_GT(norm(analytic), 0.05) << "the point must be inside the active region";
    std::vector<double> errors;
    for (double h : {1e-3, 5e-4, 2.5e-4}) {
      PotentialFieldSpec numeric = c.spec;
      numeric.gradient = GradientMethod::kCentralDifference;
      numeric.difference_step = h;
      errors.push_back(distance_between(evaluate_field(numeric, c.p, {}).F_T_W, analytic));
    }
    if (c.spec.kind == PotentialKind::kPolynomial && c.spec.order == 2 &&
        c.spec.distance.kind == DistanceKind::kPlane) {
      continue;  // quadratic U: differences are exact
    }
    ExpectSecondOrder(errors, "potential gradient");
  }
}

TEST(Fields, PolynomialOfOrderTwoIsTheLinearSpringLaw) {
  // Eq. 5.6, n = 2, over the plane z = 0: U = ½ K d², F = K d n̂ with d the depth below it.
  const PotentialFieldSpec wall = polynomial(plane_distance({0, 0, 0}, {0, 0, 1}), 2, 1000.0, 0.0);
  for (double depth : {0.001, 0.002, 0.003, 0.0125}) {
    const FieldSample s = evaluate_field(wall, {0.01, -0.02, -depth}, {});
    EXPECT_NEAR(s.F_T_W.z, 1000.0 * depth, 1e-12);
    EXPECT_EQ(s.F_T_W.x, 0.0);
    EXPECT_EQ(s.F_T_W.y, 0.0);
    EXPECT_NEAR(s.U, 0.5 * 1000.0 * depth * depth, 1e-15);
    EXPECT_TRUE(s.has_potential);
  }
  EXPECT_EQ(evaluate_field(wall, {0, 0, 0.001}, {}).F_T_W, Vec3{});  // outside: no force
  EXPECT_EQ(evaluate_field(wall, {0, 0, 0.001}, {}).U, 0.0);
  // Over a point with c = R: a solid ball, F = K (R − ρ) ρ̂, pushing outward.
  const PotentialFieldSpec ball = polynomial(point_distance({0, 0, 0}), 2, 500.0, 0.04);
  const Vec3 F = evaluate_field(ball, {0.0, 0.03, 0.0}, {}).F_T_W;
  EXPECT_NEAR(F.y, 500.0 * 0.01, 1e-12);
  // Odd order keeps U ≥ 0 and the force repulsive (eq. 5.6 written with (c − f)ⁿ).
  const PotentialFieldSpec cubic = polynomial(plane_distance({0, 0, 0}, {0, 0, 1}), 3, 1e5, 0.0);
  const FieldSample s3 = evaluate_field(cubic, {0, 0, -0.01}, {});
  EXPECT_NEAR(s3.F_T_W.z, 1e5 * 0.01 * 0.01, 1e-12);
  EXPECT_GT(s3.U, 0.0);
}

TEST(Fields, KhatibEq57GrowsWithoutBoundTowardTheSurface) {
  // n = 2: F = K (1/f − 1/f0) / f², so F f³ / (K (1 − f/f0)) = 1 as f → 0.
  const double K = 1e-9;
  const double f0 = 0.02;
  const PotentialFieldSpec field = khatib(plane_distance({0, 0, 0}, {0, 0, 1}), 2, K, f0, 1e-9);
  ASSERT_EQ(validate_field(field), "");
  double previous = 0.0;
  for (double f : {1e-2, 1e-3, 1e-4, 1e-5, 1e-6}) {
    const double F = evaluate_field(field, {0, 0, f}, {}).F_T_W.z;
    EXPECT_NEAR(F * f * f * f / (K * (1.0 - f / f0)), 1.0, 1e-12) << f;
    if (previous > 0.0) {
      EXPECT_GT(F, 900.0 * previous) << f;  // ~ 1/f³
    }
    previous = F;
  }
  EXPECT_EQ(evaluate_field(field, {0, 0, f0}, {}).F_T_W, Vec3{});  // no force beyond f0
  EXPECT_EQ(evaluate_field(field, {0, 0, 0.03}, {}).U, 0.0);
}

TEST(Fields, KhatibIsFiniteAndCappedAtEveryPointValidationAdmits) {
  const double K = 1e-9;
  const double f0 = 0.02;
  const double fm = 1e-3;
  const PotentialFieldSpec field = khatib(plane_distance({0, 0, 0}, {0, 0, 1}), 2, K, f0, fm);
  ASSERT_EQ(validate_field(field), "");
  const double cap = K * (1.0 / fm - 1.0 / f0) / (fm * fm);
  // Through the surface and beyond, including f = 0 exactly and f = f_m.
  for (int i = 0; i <= 4000; ++i) {
    const double z = 0.03 - i * 1e-5;
    const FieldSample s = evaluate_field(field, {0, 0, z}, {});
    ASSERT_TRUE(is_finite(s.F_T_W) && std::isfinite(s.U)) << z;
    ASSERT_LE(s.F_T_W.z, cap * (1.0 + 1e-12)) << z;
    ASSERT_GE(s.F_T_W.z, 0.0) << z;
  }
  EXPECT_NEAR(evaluate_field(field, {0, 0, 0}, {}).F_T_W.z, cap, 1e-12 * cap);
  EXPECT_NEAR(evaluate_field(field, {0, 0, -0.05}, {}).F_T_W.z, cap, 1e-12 * cap);
  // The cap joins the profile continuously (U is C¹ at f_m).
  const double below = evaluate_field(field, {0, 0, fm - 1e-9}, {}).F_T_W.z;
  const double above = evaluate_field(field, {0, 0, fm + 1e-9}, {}).F_T_W.z;
  EXPECT_NEAR(below, above, 1e-5 * cap);
  // Over a point, at the anchor itself (f = 0, no direction): finite and zero.
  const PotentialFieldSpec around_point = khatib(point_distance({0, 0, 0}), 2, K, f0, fm);
  EXPECT_EQ(evaluate_field(around_point, {0, 0, 0}, {}).F_T_W, Vec3{});
  EXPECT_TRUE(std::isfinite(evaluate_field(around_point, {0, 0, 0}, {}).U));
}

// ---- closed paths: conservative fields give back what they took ------------------------------

struct LoopWork {
  double net = 0.0;       // Over the closed circle. Unit: J.
  double absorbed = 0.0;  // EnergyMeter::work_in. Unit: J.
  double half = 0.0;      // Work over the first half turn. Unit: J.
  double U_start = 0.0;
  double U_half = 0.0;
};

// Drives the tool once round a circle (centre c, radius a, in the plane of e1, e2) in N steps
// of a 1 s period, metering the field's work with the trapezoidal rule.
template <typename Spec>
LoopWork circle_work(const Spec& spec, Vec3 c, double a, Vec3 e1, Vec3 e2, int N = 20000) {
  const double omega = 2.0 * std::numbers::pi;
  const double dt = 1.0 / N;
  EnergyMeter meter;
  LoopWork out;
  for (int i = 0; i <= N; ++i) {
    const double th = omega * i * dt;
    const Vec3 p = c + a * std::cos(th) * e1 + a * std::sin(th) * e2;
    const Vec3 v = (a * omega) * (-std::sin(th) * e1 + std::cos(th) * e2);
    const FieldSample s = evaluate_field(spec, p, v);
    meter.add(s.F_T_W, v, dt);
    if (i == 0) out.U_start = s.U;
    if (i == N / 2) {
      out.half = meter.work;
      out.U_half = s.U;
    }
  }
  out.net = meter.work;
  out.absorbed = meter.work_in;
  return out;
}

TEST(Fields, ConservativeFieldsReturnTheEnergyTheyTookRoundAClosedCircle) {
  const Vec3 ex{1, 0, 0};
  const Vec3 ey{0, 1, 0};
  const Vec3 ez{0, 0, 1};
  const auto check = [](const LoopWork& w, const char* what) {
    ASSERT_GT(w.absorbed, 1e-6) << what << ": the path must cross the field";
    EXPECT_LT(std::abs(w.net), 1e-6 * w.absorbed) << what;
    // Work along the open half path is the potential drop: W = U(start) − U(end).
    EXPECT_NEAR(w.half, w.U_start - w.U_half, 1e-6 * w.absorbed) << what;
  };
  // The circle (radius 3 cm about (0.02, 0, 0)) passes into and out of each field.
  const Vec3 c{0.02, 0.0, 0.0};
  // (Each centre sits off the circle: there the force turns direction and is not continuous.)
  check(circle_work(polynomial(sphere_distance({0.05, 0.01, 0}, 0.02), 2, 800.0, 0.0), c, 0.03,
                    ex, ey),
        "polynomial n=2 sphere");
  check(circle_work(polynomial(point_distance({-0.01, 0.008, 0.0}), 3, 2e5, 0.02), c, 0.03, ex, ey),
        "polynomial n=3 ball");
  check(circle_work(khatib(plane_distance({0.045, 0, 0}, {-1, 0, 0}), 2, 1e-8, 0.02, 1e-3), c,
                    0.03, ex, ey),
        "khatib plane, crossing the cap");
  check(circle_work(SpringFieldSpec{line_distance({0.04, 0.0, 0.0}, ez), 300.0, 0.0, 4.0}, c, 0.03,
                    ex, ey),
        "clipped spring to a line");
  check(circle_work(DetentFieldSpec{point_distance({0.04, 0.01, 0.0}), 0.01, 0.015, 0.004, 0.01},
                    c, 0.03, ex, ey),
        "detent");
  LinearFieldSpec linear{.origin_W = {0.02, 0.0, 0.0},
                         .force_W = {0.5, -0.3, 0.2},
                         .jacobian = {Vec3{-300, 40, 10}, Vec3{40, -200, -5}, Vec3{10, -5, -100}},
                         .radius = 0.1,
                         .fade_width = 0.02};
  const LoopWork lw = circle_work(linear, c, 0.03, ex, ey);
  EXPECT_LT(std::abs(lw.net), 1e-6 * std::max(lw.absorbed, 1e-3)) << "symmetric K";
  EXPECT_NEAR(lw.half, lw.U_start - lw.U_half, 1e-9);
}

TEST(Fields, NonSymmetricJacobianLoopWorkIsItsCurlByStokes) {
  // ∮ F·dl = ∬ (∂F_y/∂x − ∂F_x/∂y) dA = π a² (K_yx − K_xy) round a circle in the core.
  LinearFieldSpec field{.origin_W = {0.01, 0.02, 0.0},
                        .force_W = {0.2, 0.1, 0.0},
                        .jacobian = {Vec3{-100, 60, 0}, Vec3{-20, -100, 0}, Vec3{0, 0, -50}},
                        .radius = 0.08,
                        .fade_width = 0.02};
  const double a = 0.04;
  const LoopWork w = circle_work(field, field.origin_W, a, {1, 0, 0}, {0, 1, 0});
  const double expected = std::numbers::pi * a * a * (-20.0 - 60.0);
  EXPECT_NEAR(w.net, expected, 1e-6 * std::abs(expected));
  EXPECT_FALSE(evaluate_field(field, field.origin_W, {}).has_potential);  // no potential exists
}

TEST(Fields, ViscousFieldOnlyDissipates) {
  const ViscousFieldSpec everywhere{.damping = 3.0, .center_W = {}};
  // Uniform circle, radius a, period 1 s: W = −B a² ω² T.
  const double a = 0.03;
  const double omega = 2.0 * std::numbers::pi;
  const LoopWork w = circle_work(everywhere, {0, 0, 0}, a, {1, 0, 0}, {0, 1, 0});
  EXPECT_NEAR(w.net, -3.0 * a * a * omega * omega, 1e-12);
  // A wandering path through a faded sphere of influence: every power sample is ≤ 0.
  const ViscousFieldSpec local{
      .damping = 5.0, .center_W = {0.01, 0, 0}, .radius = 0.03, .fade_width = 0.01};
  ASSERT_EQ(validate_field(local), "");
  EnergyMeter meter;
  for (int i = 0; i < 5000; ++i) {
    const double t = i * 1e-3;
    const Vec3 p{0.05 * std::sin(3.1 * t), 0.03 * std::cos(2.3 * t), 0.02 * std::sin(5.7 * t)};
    const Vec3 v{0.155 * std::cos(3.1 * t), -0.069 * std::sin(2.3 * t), 0.114 * std::cos(5.7 * t)};
    const FieldSample s = evaluate_field(local, p, v);
    ASSERT_LE(dot(s.F_T_W, v), 0.0);
    EXPECT_FALSE(s.has_potential);
    meter.add(s.F_T_W, v, 1e-3);
  }
  EXPECT_EQ(meter.work_out, 0.0);
  EXPECT_LT(meter.work, 0.0);
  // Outside the sphere of influence: nothing.
  EXPECT_EQ(evaluate_field(local, {0.05, 0, 0}, {1, 1, 1}).F_T_W, Vec3{});
}

// ---- first-order field -----------------------------------------------------------------------

TEST(Fields, FirstOrderFieldIsTheLinearModelInsideFadesC1AndIsZeroOutside) {
  const LinearFieldSpec field{.origin_W = {0.01, -0.02, 0.03},
                              .force_W = {1.0, -2.0, 0.5},
                              .jacobian = {Vec3{-400, 30, 0}, Vec3{10, -300, 20}, Vec3{0, 5, -200}},
                              .radius = 0.05,
                              .fade_width = 0.01};
  ASSERT_EQ(validate_field(field), "");
  const auto linear = [&field](const Vec3& p) {
    const Vec3 d = p - field.origin_W;
    return field.force_W +
           Vec3{dot(field.jacobian[0], d), dot(field.jacobian[1], d), dot(field.jacobian[2], d)};
  };
  // The core (ρ ≤ 0.04): exactly F0 + K (p − x0).
  for (const Vec3& d : {Vec3{}, Vec3{0.01, 0, 0}, Vec3{-0.02, 0.02, 0.01}, Vec3{0, 0, -0.04}}) {
    const Vec3 p = field.origin_W + d;
    EXPECT_LT(distance_between(evaluate_field(field, p, {}).F_T_W, linear(p)), 1e-12);
  }
  // Outside the radius: zero.
  EXPECT_EQ(evaluate_field(field, field.origin_W + Vec3{0.05, 0, 0}, {}).F_T_W, Vec3{});
  EXPECT_EQ(evaluate_field(field, field.origin_W + Vec3{0, 0.03, 0.05}, {}).F_T_W, Vec3{});
  // Inside the band it is scaled by 0 < w < 1.
  const Vec3 mid = field.origin_W + Vec3{0.045, 0, 0};
  EXPECT_NEAR(distance_between(evaluate_field(field, mid, {}).F_T_W, 0.5 * linear(mid)), 0.0,
              1e-12);
  // C¹ across both edges of the band, along a radial line: values and one-sided slopes agree.
  const Vec3 dir = Vec3{2, -1, 2} * (1.0 / 3.0);
  const auto F = [&](double rho) { return evaluate_field(field, field.origin_W + rho * dir, {}).F_T_W; };
  const double eps = 1e-7;
  for (double edge : {0.04, 0.05}) {
    EXPECT_LT(distance_between(F(edge - eps), F(edge + eps)), 1e-4) << edge;
    const Vec3 slope_in = (F(edge - eps) - F(edge - 2 * eps)) * (1.0 / eps);
    const Vec3 slope_out = (F(edge + 2 * eps) - F(edge + eps)) * (1.0 / eps);
    // A merely continuous (linear) fade would jump here by |F|/fade_width, hundreds of N/m.
    EXPECT_LT(distance_between(slope_in, slope_out), 1.0) << edge;
  }
}

TEST(Fields, FirstOrderFieldReportsAPotentialOnlyForSymmetricKInTheCore) {
  LinearFieldSpec field{.origin_W = {0, 0, 0},
                        .force_W = {1.0, 0.0, 0.0},
                        .jacobian = {Vec3{-100, 20, 0}, Vec3{20, -100, 0}, Vec3{0, 0, -100}},
                        .radius = 0.05,
                        .fade_width = 0.01};
  const Vec3 d{0.01, 0.02, 0.0};
  const FieldSample s = evaluate_field(field, d, {});
  ASSERT_TRUE(s.has_potential);
  // U = −F0·δ − ½ δᵀKδ.
  const double dKd = -100 * 0.01 * 0.01 + 2 * 20 * 0.01 * 0.02 - 100 * 0.02 * 0.02;
  EXPECT_NEAR(s.U, -0.01 - 0.5 * dKd, 1e-15);
  EXPECT_FALSE(evaluate_field(field, {0.045, 0, 0}, {}).has_potential);  // fade band
  field.jacobian[0].y = 21.0;
  EXPECT_FALSE(evaluate_field(field, d, {}).has_potential);
}

// ---- springs ---------------------------------------------------------------------------------

TEST(Fields, SpringsDampOnlyAlongTheConstrainedDirections) {
  // To a line along z: a velocity along the line meets no damping; across it, −b v.
  const SpringFieldSpec to_line{line_distance({0, 0, 0}, {0, 0, 1}), 100.0, 2.0, 0.0};
  EXPECT_EQ(evaluate_field(to_line, {0, 0, 0.3}, {0, 0, 1.0}).F_T_W, Vec3{});
  const Vec3 F_line = evaluate_field(to_line, {0.01, 0, 0.3}, {0.1, 0.2, 0.5}).F_T_W;
  EXPECT_NEAR(F_line.x, -100.0 * 0.01 - 2.0 * 0.1, 1e-12);
  EXPECT_NEAR(F_line.y, -2.0 * 0.2, 1e-12);
  EXPECT_EQ(F_line.z, 0.0);
  // To a plane z = 0.01: only the normal component is pulled and damped (bilateral).
  const SpringFieldSpec to_plane{plane_distance({0, 0, 0.01}, {0, 0, 3}), 200.0, 1.0, 0.0};
  const FieldSample above = evaluate_field(to_plane, {0.5, -0.5, 0.02}, {1.0, 1.0, 0.1});
  EXPECT_NEAR(above.F_T_W.z, -200.0 * 0.01 - 0.1, 1e-12);
  EXPECT_EQ(above.F_T_W.x, 0.0);
  EXPECT_EQ(above.F_T_W.y, 0.0);
  EXPECT_NEAR(above.U, 0.5 * 200.0 * 0.01 * 0.01, 1e-15);
  EXPECT_NEAR(evaluate_field(to_plane, {0, 0, 0.0}, {}).F_T_W.z, 200.0 * 0.01, 1e-12);
  // To a point: all three directions.
  const SpringFieldSpec to_point{point_distance({0.01, 0, 0}), 50.0, 0.5, 0.0};
  const Vec3 F_point = evaluate_field(to_point, {0.03, 0.01, 0}, {0.1, 0, -0.2}).F_T_W;
  EXPECT_NEAR(F_point.x, -50.0 * 0.02 - 0.05, 1e-12);
  EXPECT_NEAR(F_point.y, -50.0 * 0.01, 1e-12);
  EXPECT_NEAR(F_point.z, 0.1, 1e-12);
}

TEST(Fields, MaxForceClipsTheTotalAndKeepsItsDirection) {
  const SpringFieldSpec spring{point_distance({0, 0, 0}), 1000.0, 0.0, 2.0};
  EXPECT_NEAR(evaluate_field(spring, {0.001, 0, 0}, {}).F_T_W.x, -1.0, 1e-12);  // below the clip
  const Vec3 p{0.006, 0.008, 0.0};  // 10 mm: 10 N unclipped
  const FieldSample s = evaluate_field(spring, p, {});
  EXPECT_NEAR(norm(s.F_T_W), 2.0, 1e-12);
  EXPECT_NEAR(s.F_T_W.x, -1.2, 1e-12);
  EXPECT_NEAR(s.F_T_W.y, -1.6, 1e-12);
  EXPECT_NEAR(s.U, 2.0 * 0.01 - 2.0 * 2.0 / 2000.0, 1e-15);  // F_max |f| − F_max²/2k
  // With damping the total is clipped too.
  const SpringFieldSpec damped{point_distance({0, 0, 0}), 1000.0, 50.0, 2.0};
  EXPECT_NEAR(norm(evaluate_field(damped, {0.001, 0, 0}, {0.1, 0, 0}).F_T_W), 2.0, 1e-12);
  const SpringFieldSpec unclipped{point_distance({0, 0, 0}), 1000.0, 0.0, 0.0};
  EXPECT_NEAR(norm(evaluate_field(unclipped, p, {}).F_T_W), 10.0, 1e-12);
}

// ---- detent ----------------------------------------------------------------------------------

TEST(Fields, DetentPullsInsidePushesOutOnTheRimAndIsZeroFarAway) {
  const Vec3 c{0.01, 0.02, -0.01};
  const DetentFieldSpec detent{point_distance(c), 0.02, 0.01, 0.005, 0.004};
  ASSERT_EQ(validate_field(detent), "");
  const Vec3 dir = Vec3{1, 2, -2} * (1.0 / 3.0);
  const auto at = [&](double rho) { return evaluate_field(detent, c + rho * dir, {}); };
  for (double rho = 0.0005; rho < 0.0100; rho += 0.0005) {
    EXPECT_LT(dot(at(rho).F_T_W, dir), 0.0) << rho;  // toward the centre
  }
  for (double rho = 0.0102; rho < 0.014; rho += 0.0004) {
    EXPECT_GT(dot(at(rho).F_T_W, dir), 0.0) << rho;  // outward on the rim
  }
  for (double rho : {0.014, 0.02, 0.5}) {
    EXPECT_EQ(at(rho).F_T_W, Vec3{}) << rho;
    EXPECT_EQ(at(rho).U, 0.0) << rho;
  }
  EXPECT_DOUBLE_EQ(at(0.0).U, -0.02);  // −D at the centre
  EXPECT_DOUBLE_EQ(at(0.01).U, 0.005);  // H on the crest
  EXPECT_EQ(at(0.0).F_T_W, Vec3{});
  // Strongest pull 1.5 (D + H)/R at R/2; strongest push 1.5 H/w mid-slope.
  EXPECT_NEAR(-dot(at(0.005).F_T_W, dir), 1.5 * 0.025 / 0.01, 1e-12);
  EXPECT_NEAR(dot(at(0.012).F_T_W, dir), 1.5 * 0.005 / 0.004, 1e-12);
  // Near the centre a spring of stiffness 6 (D + H)/R².
  EXPECT_NEAR(-dot(at(1e-6).F_T_W, dir) / 1e-6, 6.0 * 0.025 / 1e-4, 1e-3 * 1500.0);
  // Continuous at the crest and at the rim's outer edge.
  for (double edge : {0.01, 0.014}) {
    EXPECT_LT(distance_between(at(edge - 1e-9).F_T_W, at(edge + 1e-9).F_T_W), 1e-5) << edge;
  }
  // Over a line: a groove; the force is normal to the line.
  const DetentFieldSpec groove{line_distance({0, 0, 0}, {1, 0, 0}), 0.02, 0.01, 0.0, 0.004};
  const Vec3 F = evaluate_field(groove, {0.3, 0.004, 0.0}, {}).F_T_W;
  EXPECT_EQ(F.x, 0.0);
  EXPECT_LT(F.y, 0.0);
}

// ---- degenerate points -----------------------------------------------------------------------

TEST(Fields, NoNaNWhenTheToolSitsExactlyOnAnAnchor) {
  const Vec3 a{0.01, -0.02, 0.03};
  const Vec3 v{0.1, -0.2, 0.3};
  const std::vector<EnergyFieldSpec> fields = {
      SpringFieldSpec{point_distance(a), 100.0, 1.0, 5.0},
      SpringFieldSpec{line_distance(a, {1, 1, 0}), 100.0, 1.0, 0.0},
      SpringFieldSpec{plane_distance(a, {0, 0, 1}), 100.0, 1.0, 0.0},
      SpringFieldSpec{sphere_distance(a, 0.02), 100.0, 1.0, 0.0},
      polynomial(point_distance(a), 2, 1000.0, 0.01),
      polynomial(line_distance(a, {0, 1, 0}), 3, 1e5, 0.01),
      polynomial(sphere_distance(a, 0.02), 2, 1000.0, 0.0),
      khatib(point_distance(a), 2, 1e-9, 0.02, 1e-4),
      khatib(line_distance(a, {0, 0, 1}), 2, 1e-9, 0.02, 1e-4),
      DetentFieldSpec{point_distance(a), 0.01, 0.01, 0.002, 0.005},
      DetentFieldSpec{line_distance(a, {1, 0, 0}), 0.01, 0.01, 0.002, 0.005},
      LinearFieldSpec{a, {1, 2, 3}, {Vec3{-1, 0, 0}, Vec3{0, -1, 0}, Vec3{0, 0, -1}}, 0.02, 0.02},
      ViscousFieldSpec{2.0, a, 0.02, 0.02},
  };
  for (std::size_t i = 0; i < fields.size(); ++i) {
    ASSERT_EQ(validate_field(fields[i]), "") << i;
    for (GradientMethod method : {GradientMethod::kAnalytic, GradientMethod::kCentralDifference}) {
      EnergyFieldSpec spec = fields[i];
      if (auto* potential = std::get_if<PotentialFieldSpec>(&spec)) potential->gradient = method;
      const FieldSample s = evaluate_field(spec, a, v);
      EXPECT_TRUE(is_finite(s.F_T_W)) << i;
      EXPECT_TRUE(std::isfinite(s.U)) << i;
    }
  }
  // Exactly on a point anchor the spring pulls nowhere (damping still acts).
  EXPECT_EQ(evaluate_field(fields[0], a, {}).F_T_W, Vec3{});
}

// ---- validation ------------------------------------------------------------------------------

TEST(Fields, ValidationNamesTheBadParameter) {
  const auto starts = [](const std::string& message, const std::string& prefix) {
    return message.rfind(prefix, 0) == 0;
  };
  // Usable specs pass.
  EXPECT_EQ(validate_field(polynomial(sphere_distance({0, 0, 0}, 0.1), 2, 10.0, 0.0)), "");
  EXPECT_EQ(validate_field(khatib(plane_distance({0, 0, 0}, {0, 0, 1}), 2, 1.0, 0.01, 1e-3)), "");
  EXPECT_EQ(validate_field(EnergyFieldSpec{ViscousFieldSpec{.damping = 1.0, .center_W = {}}}), "");

  // Potentials.
  EXPECT_TRUE(starts(validate_field(polynomial(point_distance({0, 0, 0}), 1, 10.0, 0.01)),
                     "order: must be an integer in [2, 8], got 1"));
  EXPECT_TRUE(starts(validate_field(polynomial(point_distance({kNaN, 0, 0}), 2, 10.0, 0.01)),
                     "distance.origin_W: must be finite"));
  EXPECT_TRUE(starts(validate_field(polynomial(line_distance({0, 0, 0}, {}), 2, 10.0, 0.01)),
                     "distance.axis_W: must be finite with norm > 1e-12, got (0, 0, 0)"));
  EXPECT_TRUE(starts(validate_field(polynomial(sphere_distance({0, 0, 0}, 0.0), 2, 1.0, 0.0)),
                     "distance.radius: must be finite and > 0, got 0"));
  EXPECT_TRUE(starts(validate_field(polynomial(point_distance({0, 0, 0}), 2, kInf, 0.01)),
                     "gain: must be finite and >= 0"));
  EXPECT_TRUE(starts(validate_field(polynomial(point_distance({0, 0, 0}), 2, 10.0, kNaN)),
                     "offset: must be finite"));
  EXPECT_TRUE(starts(validate_field(polynomial(point_distance({0, 0, 0}), 2, 10.0, 101.0)),
                     "offset: must be finite and within ±100 m, got 101"));
  // Finite numbers whose force is not: gain (c − f)⁷ overflows far from the surface. Refused, so
  // that no client can make the loop's force non-finite (the guard would fault it every tick).
  EXPECT_TRUE(starts(validate_field(polynomial(point_distance({0, 0, 0}), 8, 1e303, 10.0)),
                     "gain: too large: the force 100 m inside the surface overflows"));
  EXPECT_EQ(validate_field(polynomial(point_distance({0, 0, 0}), 8, 1e200, 10.0)), "");  // big, finite
  PotentialFieldSpec step = polynomial(point_distance({0, 0, 0}), 2, 10.0, 0.01);
  step.difference_step = 0.0;
  EXPECT_TRUE(starts(validate_field(step), "difference_step:"));
  const DistanceSpec plane = plane_distance({0, 0, 0}, {0, 0, 1});
  EXPECT_TRUE(starts(validate_field(khatib(plane, 2, 1.0, 0.0, 0.0)),
                     "influence_distance: must be finite and > 0, got 0"));
  EXPECT_TRUE(starts(validate_field(khatib(plane, 2, 1.0, -0.01, 0.001)), "influence_distance:"));
  EXPECT_TRUE(starts(validate_field(khatib(plane, 2, 1.0, 0.01, 0.0)), "min_distance:"));
  EXPECT_TRUE(starts(validate_field(khatib(plane, 2, 1.0, 0.01, 0.01)), "min_distance:"));
  EXPECT_TRUE(starts(validate_field(khatib(plane, 8, 1.0, 0.01, 1e-60)),
                     "min_distance: too small"));  // the capped force itself overflows

  // Springs.
  EXPECT_TRUE(starts(validate_field(SpringFieldSpec{plane_distance({0, 0, 0}, {kInf, 0, 0}), 1.0,
                                                    0.0, 0.0}),
                     "anchor.axis_W:"));
  EXPECT_TRUE(starts(validate_field(SpringFieldSpec{point_distance({}), -1.0, 0.0, 0.0}),
                     "stiffness: must be finite and >= 0, got -1"));
  EXPECT_TRUE(starts(validate_field(SpringFieldSpec{point_distance({}), 1.0, kNaN, 0.0}),
                     "damping:"));
  EXPECT_TRUE(starts(validate_field(SpringFieldSpec{point_distance({}), 1.0, 0.0, -2.0}),
                     "max_force:"));

  // First-order field.
  LinearFieldSpec linear{.origin_W = {}, .force_W = {}, .radius = 0.05, .fade_width = 0.01};
  EXPECT_EQ(validate_field(linear), "");
  linear.jacobian[1].z = kInf;
  EXPECT_TRUE(starts(validate_field(linear), "jacobian[1]: must be finite, got (0, 0, inf)"));
  linear.jacobian[1].z = 0.0;
  linear.fade_width = 0.0;
  EXPECT_TRUE(starts(validate_field(linear), "fade_width:"));  // a cut-out, not a fade
  linear.fade_width = 0.06;
  EXPECT_TRUE(starts(validate_field(linear), "fade_width:"));
  linear.fade_width = 0.01;
  linear.force_W.y = kNaN;
  EXPECT_TRUE(starts(validate_field(linear), "force_W:"));
  EXPECT_TRUE(starts(validate_field(LinearFieldSpec{}), "radius:"));

  // Viscous field and detent.
  EXPECT_TRUE(starts(validate_field(ViscousFieldSpec{.damping = -1.0, .center_W = {}}), "damping:"));
  EXPECT_TRUE(starts(validate_field(ViscousFieldSpec{.damping = 1.0, .center_W = {}, .radius = 0.02}),
                     "fade_width:"));
  const DistanceSpec centre = point_distance({});
  EXPECT_TRUE(starts(validate_field(DetentFieldSpec{centre, 0.0, 0.01, 0.0, 0.01}), "depth:"));
  EXPECT_TRUE(starts(validate_field(DetentFieldSpec{centre, 0.01, kNaN, 0.0, 0.01}), "radius:"));
  EXPECT_TRUE(
      starts(validate_field(DetentFieldSpec{centre, 0.01, 0.01, -1.0, 0.01}), "rim_height:"));
  EXPECT_TRUE(
      starts(validate_field(DetentFieldSpec{centre, 0.01, 0.01, 0.0, 0.0}), "rim_width:"));
}

// ---- energy meter ----------------------------------------------------------------------------

TEST(Fields, EnergyMeterIntegratesPowerByTheTrapezoidalRule) {
  EnergyMeter meter;
  meter.add({2, 0, 0}, {0.5, 0, 0}, 0.001);  // first sample: only records P = 1 W
  EXPECT_EQ(meter.work, 0.0);
  // Power ramps linearly from 1 W to 3 W over 1 s: trapezoids integrate it exactly, 2 J.
  for (int i = 1; i <= 1000; ++i) meter.add({2, 0, 0}, {0.5 + i * 1e-3, 0, 0}, 0.001);
  EXPECT_NEAR(meter.work, 2.0, 1e-12);
  EXPECT_NEAR(meter.work_out, 2.0, 1e-12);
  EXPECT_EQ(meter.work_in, 0.0);
  // Reversed power is absorbed: work_in grows, the net falls.
  for (int i = 0; i < 1000; ++i) meter.add({-2, 0, 0}, {1.0, 0, 0}, 0.001);
  EXPECT_GT(meter.work_in, 1.9);
  EXPECT_NEAR(meter.work, meter.work_out - meter.work_in, 1e-12);
  meter.reset();
  EXPECT_EQ(meter.work, 0.0);
  EXPECT_FALSE(meter.has_last);
}

// ---- real-time ---------------------------------------------------------------------------------

TEST(Fields, EvaluationAndMeteringAllocateNothing) {
  const std::vector<EnergyFieldSpec> fields = {
      polynomial(sphere_distance({0, 0, 0}, 0.02), 3, 1e5, 0.0),
      khatib(plane_distance({0, 0, -0.03}, {0, 0, 1}), 2, 1e-9, 0.02, 1e-4),
      PotentialFieldSpec{.distance = point_distance({0.01, 0, 0}),
                         .gain = 500.0,
                         .offset = 0.02,
                         .gradient = GradientMethod::kCentralDifference},
      SpringFieldSpec{line_distance({0, 0, 0}, {0, 0, 1}), 200.0, 1.0, 3.0},
      LinearFieldSpec{{0, 0, 0}, {1, 0, 0}, {Vec3{-50, 0, 0}, Vec3{0, -50, 0}, Vec3{}}, 0.04, 0.01},
      ViscousFieldSpec{2.0, {0, 0, 0}, 0.03, 0.01},
      DetentFieldSpec{point_distance({0.01, 0.01, 0}), 0.01, 0.01, 0.003, 0.005},
  };
  std::vector<EnergyMeter> meters(fields.size());
  Vec3 total;
  haptic::test::reset_allocations();
  {
    haptic::test::CountAllocations counting;
    for (int tick = 0; tick < 2000; ++tick) {
      const Vec3 p{0.03 * std::sin(tick * 0.003), 0.03 * std::cos(tick * 0.005),
                   0.02 * std::sin(tick * 0.007)};
      const Vec3 v{0.09 * std::cos(tick * 0.003), -0.15 * std::sin(tick * 0.005), 0.0};
      for (std::size_t i = 0; i < fields.size(); ++i) {
        const FieldSample s = evaluate_field(fields[i], p, v);
        meters[i].add(s.F_T_W, v, 1e-3);
        total += s.F_T_W;
      }
    }
  }
  EXPECT_EQ(haptic::test::allocations(), 0u);
  EXPECT_TRUE(is_finite(total));
  EXPECT_GT(norm(total), 0.0);
}

}  // namespace
}  // namespace haptic::engine
