// The 1-DOF DC-motor device and its controllers (Monasterio-Huelin, Gutiérrez, Larraga,
// "Introduction to Haptic Systems"): the spring-damper discretizations of section 8, gravity
// compensation (eq. 6.7), the inductance-free model (eq. 3.9) against the full one
// (eqs. 2.1–2.4, 3.8), the haptic loop (eqs. 9.6–9.7) and parameter validation.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "engine/control/dc_motor_control.hpp"
#include "engine/device/dc_motor_plant.hpp"

namespace haptic::engine {
namespace {

constexpr double kT = 1e-3;  // s, the 1 kHz haptic period (section 7)
constexpr double kPi = std::numbers::pi;

constexpr auto kNoHand = [](double, double) { return ExternalWrench{}; };
constexpr auto kNoObserver = [](std::uint64_t, const DcMotorState&, double) {};

// ---------------------------------------------------------------------------------------------
// Section 8: discretizations of τ_V = k_V θ_V + B_V θ̇_V (eq. 8.1).

TEST(SpringDamperDiscretization, ExactWeightsSumToTheStiffness_Eq8_12) {
  for (const double k_V : {0.01, 1.0, 50.0, 1000.0}) {
    for (const double B_V : {1e-3, 0.02, 0.5}) {
      for (const double T : {1e-5, 1e-4, 1e-3, 1e-2}) {
        const SpringDamperCoefficients a = exact_delayed_coefficients(k_V, B_V, T);
        ASSERT_TRUE(std::isfinite(a.c1) && std::isfinite(a.c2));
        // Round-off scales with the weights themselves (≈ B_V / T when k_V T / B_V is small).
        const double tolerance = 1e-12 * (std::abs(a.c1) + k_V);
        EXPECT_NEAR(a.c1 + a.c2, k_V, tolerance) << "k_V " << k_V << " B_V " << B_V << " T " << T;
        // Eq. 8.12a as printed, and 8.12b corrected (see the test below), where they do not
        // overflow.
        const double x = k_V * T / B_V;
        if (x < 50.0) {
          EXPECT_NEAR(a.c1, k_V * std::exp(x) / (std::exp(x) - 1.0), 1e-9 * std::abs(a.c1));
          EXPECT_NEAR(a.c2, -k_V / (std::exp(x) - 1.0), 1e-9 * std::abs(a.c1));
        }
      }
    }
  }
}

// Eq. 8.12b is garbled as printed, a2 = −k_V / (k_V / e^{k_V T/B_V} − 1) (000, L486): with it the
// weights do not sum to k_V (the spring would not rest where eq. 8.19 says), and it is not eq.
// 8.10b's a2 either. The form used, −k_V / (e^{k_V T/B_V} − 1), is the one a1 + a2 = k_V (stated
// after eq. 8.19) and eq. 8.10b's −k_V e^{−x} / (1 − e^{−x}) both give.
TEST(SpringDamperDiscretization, Eq8_12bAsPrintedIsGarbledTheCorrectedFormSumsToTheStiffness) {
  const double k_V = 50.0, B_V = 0.02, T = 1e-3;
  const double x = k_V * T / B_V;  // 2.5
  const SpringDamperCoefficients a = exact_delayed_coefficients(k_V, B_V, T);
  const double printed_a2 = -k_V / (k_V / std::exp(x) - 1.0);
  const double from_8_10b = -k_V * std::exp(-x) / (1.0 - std::exp(-x));
  EXPECT_NEAR(a.c2, from_8_10b, 1e-12 * k_V);
  EXPECT_NEAR(a.c1 + a.c2, k_V, 1e-12 * k_V);
  EXPECT_GT(std::abs(a.c1 + printed_a2 - k_V), 0.2 * k_V);  // as printed: 38.4, 23 % short of k_V
}

// Eq. 9.4 repeats eq. 8.19's rest term, −a_V θ_m0 (000, L555): at rest, θ_m(k) = θ_m(k−1) = θ_m0,
// it leaves b_V θ_m0 of torque, so the spring would push at its own rest angle. Substituting eq.
// 8.18a into eq. 8.11 gives −(a_V + b_V) θ_m0 = −r k_V θ_m0 (as eq. 9.5 and 9.7 carry), which is
// what VirtualTorsionSpring applies: zero torque at rest.
TEST(VirtualTorsionSpring, AtItsRestAngleItsTorqueIsZeroUnlikeEq9_4AsPrinted) {
  const double k_V = 20.0, B_V = 0.05, T = 1e-3, r = 0.1, theta_m0 = 3.0;
  const SpringDamperCoefficients a = exact_delayed_coefficients(k_V, B_V, T);
  VirtualTorsionSpring spring(a, r, theta_m0);
  spring.reset(theta_m0);
  EXPECT_EQ(spring.torque(theta_m0), 0.0);
  const double a_V = r * a.c1, b_V = r * (k_V - a.c1);
  EXPECT_NEAR(a_V + b_V, r * k_V, 1e-12);  // "It is also met that a_V + b_V = r k_V"
  const double printed = a_V * theta_m0 + b_V * theta_m0 - a_V * theta_m0;  // eq. 9.4 at rest
  EXPECT_NEAR(printed, b_V * theta_m0, 1e-12);
  EXPECT_GT(std::abs(printed), 1.0);  // a torque at rest: the printed rest term is wrong
}

// Eq. 9.5 prints θ_m where the damping term needs θ̇_m (000, L580): τ_V = r k_V θ_m + r B_V θ_m −
// r k_V θ_m0 as printed has no velocity in it, and eq. 9.7, which the document derives from it,
// carries r B_V on θ̇_m. The discrete spring of eq. 9.4 (rest term corrected) on a ramp θ_m(t) =
// θ_m0 + v t approaches the corrected form r k_V (θ_m − θ_m0) + r B_V θ̇_m as T → 0 (first order:
// c1 θ(k) + c2 θ(k−1) = k_V θ(k) − c2 v T and −c2 T = k_V T / (e^x − 1) → B_V), while the printed
// form stays a whole r B_V (θ_m − v) away.
TEST(VirtualTorsionSpring, TendsToEq9_5WithTheVelocityNotThePositionInItsDampingTerm) {
  const double k_V = 20.0, B_V = 0.05, r = 0.1, theta_m0 = 3.0, t = 0.05;
  for (const double v : {-4.0, 1.0, 6.0}) {  // rad/s at the motor axis
    for (const double T : {1e-3, 1e-4, 1e-5}) {
      VirtualTorsionSpring spring(exact_delayed_coefficients(k_V, B_V, T), r, theta_m0);
      const auto ticks = static_cast<std::uint64_t>(std::llround(t / T));
      spring.reset(theta_m0);
      double tau = 0.0;
      double theta = theta_m0;
      for (std::uint64_t k = 1; k <= ticks; ++k) {
        theta = theta_m0 + v * static_cast<double>(k) * T;
        tau = spring.torque(theta);
      }
      const double corrected = r * k_V * (theta - theta_m0) + r * B_V * v;
      const double printed = r * k_V * theta + r * B_V * theta - r * k_V * theta_m0;
      // The first-order error: −c2 T = B_V (1 − x/2 + x²/12 − …), x = k_V T / B_V, so τ falls short
      // by r k_V v T / 2 to within x/6 of it (0.4 at T = 1 ms).
      const double first_order = r * k_V * std::abs(v) * T / 2.0;
      EXPECT_NEAR(std::abs(tau - corrected), first_order, 0.07 * first_order) << "v " << v << " T " << T;
      // Against the printed form, the whole damping term's difference, r B_V (v − θ_m).
      EXPECT_NEAR(tau - printed, r * B_V * (v - theta), 1.1 * first_order) << "v " << v << " T " << T;
      if (T <= 1e-4) {  // the two forms are told apart
        EXPECT_GT(r * B_V * std::abs(v - theta), 10.0 * first_order) << "v " << v << " T " << T;
      }
    }
  }
}

// b_i → a_i as T → 0 (eqs. 8.16, 8.17). The relative difference vanishes; the absolute one does
// not: with x = k_V T / B_V, a1 − b1 = k_V (1/(eˣ − 1) − 1/x) → −k_V / 2, and a2 − b2 → +k_V / 2,
// while both weights grow like B_V / T. So the relative difference is ≈ x / 2: first order in T.
TEST(SpringDamperDiscretization, EulerWeightsApproachTheExactOnesAtFirstOrder_Eq8_16) {
  const double k_V = 1.0;
  const double B_V = 0.02;
  std::vector<double> log_T;
  std::vector<double> log_error;
  std::printf("  T [s]     a1          b1          a2          b2          max rel. diff\n");
  for (const double T : {1e-2, 1e-3, 1e-4, 1e-5}) {
    const SpringDamperCoefficients a = exact_delayed_coefficients(k_V, B_V, T);
    const SpringDamperCoefficients b = euler_backward_coefficients(k_V, B_V, T);
    const double error =
        std::max(std::abs(b.c1 - a.c1) / std::abs(a.c1), std::abs(b.c2 - a.c2) / std::abs(a.c2));
    std::printf("  %.0e  %-10.6g  %-10.6g  %-10.6g  %-10.6g  %.4g\n", T, a.c1, b.c1, a.c2, b.c2,
                error);
    log_T.push_back(std::log(T));
    log_error.push_back(std::log(error));
    EXPECT_NEAR(a.c1 - b.c1, -k_V / 2.0, 0.1 * k_V);  // the absolute gap stays ≈ k_V / 2
  }
  // Least-squares slope of log(error) against log(T): the observed order.
  const double n = static_cast<double>(log_T.size());
  double sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;
  for (std::size_t k = 0; k < log_T.size(); ++k) {
    sx += log_T[k];
    sy += log_error[k];
    sxx += log_T[k] * log_T[k];
    sxy += log_T[k] * log_error[k];
  }
  const double order = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  std::printf("  observed order %.4f\n", order);
  RecordProperty("observed_order", std::to_string(order));
  EXPECT_NEAR(order, 1.0, 0.05);
}

// ---------------------------------------------------------------------------------------------
// Parameters.

TEST(DcMotorParams, DefaultsAreValidAndTheTimeConstantsMatchTheDataSheet_Eq2_5) {
  const DcMotorParams p;
  EXPECT_EQ(p.validate(), "");
  EXPECT_NEAR(p.t_e(), 0.329e-3 / 1.16, 1e-12);
  EXPECT_NEAR(p.t_m(), 4.28e-3, 0.03e-3);  // the data sheet's mechanical time constant
  EXPECT_LT(p.t_e(), 0.1 * p.t_m());       // t_e ≪ t_m (section 2)
}

TEST(DcMotorParams, ValidateNamesTheBadParameter) {
  const auto message = [](auto change) {
    DcMotorParams p;
    change(p);
    return p.validate();
  };
  EXPECT_EQ(message([](DcMotorParams& p) { p.r = 0.0; }).rfind("r: ", 0), 0u);
  EXPECT_EQ(message([](DcMotorParams& p) { p.r = 1.5; }).rfind("r: ", 0), 0u);
  EXPECT_EQ(message([](DcMotorParams& p) { p.eta = 0.0; }).rfind("eta: ", 0), 0u);
  EXPECT_EQ(message([](DcMotorParams& p) { p.m = std::numeric_limits<double>::quiet_NaN(); })
                .rfind("m: ", 0),
            0u);
  EXPECT_EQ(message([](DcMotorParams& p) { p.m = -1.0; }).rfind("m: ", 0), 0u);
  EXPECT_EQ(message([](DcMotorParams& p) { p.R_m = 0.0; }).rfind("R_m: ", 0), 0u);
  EXPECT_EQ(message([](DcMotorParams& p) { p.r = 1.0; }), "");  // a direct drive is allowed
  std::printf("  e.g. \"%s\"\n", message([](DcMotorParams& p) { p.r = 1.5; }).c_str());
}

// Eqs. 4.3–4.5: a force tangential to the link (counter-clockwise) of size f gives τ_e = l f.
TEST(DcMotorPlant, TangentialForceGivesLTimesForce_Eq4_5) {
  DcMotorParams p;
  p.alpha_c = 0.3;
  for (const double theta_L : {-1.0, 0.0, 0.7, 2.5}) {
    const double a = theta_L + p.alpha_c;
    const ExternalWrench F{{-2.0 * std::sin(a), 2.0 * std::cos(a), 7.0}, {1.0, 1.0, 0.1}};
    EXPECT_NEAR(external_joint_torque(p, theta_L, F), p.l * 2.0 + 0.1, 1e-12);
    const ExternalWrench normal{{std::cos(a), std::sin(a), 0.0}, {}};  // along the link: no work
    EXPECT_NEAR(external_joint_torque(p, theta_L, normal), 0.0, 1e-12);
  }
}

// ---------------------------------------------------------------------------------------------
// Section 6: gravity compensation u = −K_D θ̇_m + (r/η) τ_g(θ_m) (eq. 6.7), sampled at 1 kHz.

constexpr double kGravityK_D = 5e-3;  // N·m·s/rad

/// Runs eq. 6.7 for `ticks` periods; returns the state.
DcMotorState run_gravity_compensation(DcMotorPlant& plant, int ticks) {
  const DcMotorParams& p = plant.params();
  for (int k = 0; k < ticks; ++k) {
    const DcMotorState& s = plant.state();
    plant.step(voltage_from_torque_command(
                   p, gravity_compensation(p, kGravityK_D, s.theta_m, s.omega_m)),
               kT);
  }
  return plant.state();
}

/// The device let go at theta_L with load velocity omega_L, with the current the controller was
/// driving at that moment (the hand held or moved it with the controller running).
DcMotorState released_at(const DcMotorParams& p, double theta_L, double omega_L) {
  DcMotorState s{theta_L / p.r, omega_L / p.r, 0.0};
  const double u_m = voltage_from_torque_command(
      p, gravity_compensation(p, kGravityK_D, s.theta_m, s.omega_m));
  s.i = (u_m - p.k_b * s.omega_m) / p.R_m;
  return s;
}

class GravityCompensation : public ::testing::TestWithParam<DcMotorModel> {};

TEST_P(GravityCompensation, ReleasedAtRestTheLoadHoldsItsAngle_Eq6_7) {
  const DcMotorParams p;
  for (const double deg : {-60.0, 0.0, 30.0, 80.0}) {
    const double theta_L = deg * kPi / 180.0;
    DcMotorPlant plant(p, GetParam(), released_at(p, theta_L, 0.0));
    const DcMotorState end = run_gravity_compensation(plant, 3000);
    // Perfect cancellation makes the release point an equilibrium of the sampled loop too; what
    // is left is round-off.
    EXPECT_NEAR(p.r * end.theta_m, theta_L, 1e-9) << deg << " deg";
    EXPECT_NEAR(end.omega_m, 0.0, 1e-9) << deg << " deg";
  }
}

/// e^{M h} for a 4×4 matrix, by scaling and squaring a Taylor series (exact to round-off for the
/// norms here, |M h| < 4): the sampled-data model below, independent of the plant's integrator.
using Matrix4 = std::array<std::array<double, 4>, 4>;
Matrix4 multiply(const Matrix4& a, const Matrix4& b) {
  Matrix4 c{};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k) c[i][j] += a[i][k] * b[k][j];
  return c;
}
Matrix4 expm(Matrix4 m, double h) {
  constexpr int kHalvings = 10;
  for (auto& row : m)
    for (double& x : row) x *= h / (1 << kHalvings);
  Matrix4 sum{}, term{};
  for (int i = 0; i < 4; ++i) sum[i][i] = term[i][i] = 1.0;
  for (int n = 1; n <= 20; ++n) {
    term = multiply(term, m);
    for (auto& row : term)
      for (double& x : row) x /= n;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) sum[i][j] += term[i][j];
  }
  for (int k = 0; k < kHalvings; ++k) sum = multiply(sum, sum);
  return sum;
}

/// The coast of eq. 6.7's sampled loop from motor speed ω0, gravity cancelled: the linear model of
/// section 2-3 (deviations from the gravity-holding current), its input −K_D θ̇_m(t_k) held over
/// each tick, stepped exactly with e^{A T}. State [θ_m, θ̇_m, i, u_m]; without inductance the
/// current follows the voltage at once (eq. 2.6). Unit: rad (motor).
double sampled_coast(const DcMotorParams& p, DcMotorModel model, double omega0) {
  Matrix4 a{};  // d/dt [θ, ω, i, u]; u is held: its row stays zero
  a[0][1] = 1.0;
  if (model == DcMotorModel::kWithInductance) {
    a[1][1] = -p.B_m / p.J_eff();
    a[1][2] = p.k_m / p.J_eff();
    a[2][1] = -p.k_b / p.L_m;
    a[2][2] = -p.R_m / p.L_m;
    a[2][3] = 1.0 / p.L_m;
  } else {
    a[1][1] = -p.B() / p.J_eff();
    a[1][3] = p.k_m / p.R_m / p.J_eff();
  }
  const Matrix4 phi = expm(a, kT);
  const double u_per_omega = -p.R_m / p.k_m * kGravityK_D;  // eq. 6.7's damping, as a voltage
  std::array<double, 4> x{0.0, omega0, (u_per_omega * omega0 - p.k_b * omega0) / p.R_m, 0.0};
  for (int k = 0; k < 100000 && std::abs(x[1]) > 1e-12 * std::abs(omega0); ++k) {
    x[3] = u_per_omega * x[1];
    std::array<double, 4> next{};
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) next[i] += phi[i][j] * x[j];
    x = next;
  }
  return x[0];
}

// Let go while moving: with perfect cancellation eq. 6.5/6.6 leave J_eff θ̈_m = −(B + K_D) θ̇_m,
// so the motor coasts ω0 J_eff / (B + K_D) and stops — in continuous time. The sampled loop holds
// −K_D θ̇_m from the start of each tick, larger than its mean over the tick, so it brakes harder
// and the coast is shorter; with inductance the current also lags the voltage by t_e = 0.28 ms.
// Both are exact in sampled_coast(), which the plant must match to 0.1 % (what is left is the
// gravity term, held over a tick while the link turns by at most r ω0 T = 0.5 mrad, and the
// integrator's error). Holding: over the last second the angle moves less than 1e-9 rad.
TEST_P(GravityCompensation, ReleasedMovingTheLoadComesToRestAndHolds_Eq6_7) {
  const DcMotorParams p;
  const double omega_L0 = 0.5;  // rad/s at the load
  const double continuous = omega_L0 / p.r * p.J_eff() / (p.B() + kGravityK_D);
  const double sampled = sampled_coast(p, GetParam(), omega_L0 / p.r);
  EXPECT_LT(sampled, continuous);  // the held damping brakes harder
  for (const double deg : {-60.0, 0.0, 30.0, 80.0}) {
    const double theta_L = deg * kPi / 180.0;
    DcMotorPlant plant(p, GetParam(), released_at(p, theta_L, omega_L0));
    const DcMotorState at_2s = run_gravity_compensation(plant, 2000);
    const DcMotorState at_3s = run_gravity_compensation(plant, 1000);
    const double coast = at_3s.theta_m - theta_L / p.r;
    std::printf("  %5.1f deg: coast %.6f rad (motor), sampled-data model %.6f, continuous-time %.6f\n",
                deg, coast, sampled, continuous);
    EXPECT_NEAR(coast, sampled, 0.001 * sampled) << deg << " deg";
    EXPECT_NEAR(at_3s.omega_m, 0.0, 1e-9) << deg << " deg";
    EXPECT_NEAR(at_3s.theta_m, at_2s.theta_m, 1e-9) << deg << " deg";
  }
}

INSTANTIATE_TEST_SUITE_P(Models, GravityCompensation,
                         ::testing::Values(DcMotorModel::kWithInductance,
                                           DcMotorModel::kWithoutInductance));

// Without compensation the link falls: the compensation is doing the holding.
TEST(GravityCompensation, WithoutTheGravityTermTheLinkFalls) {
  const DcMotorParams p;
  DcMotorPlant plant(p, DcMotorModel::kWithoutInductance, {0.0, 0.0, 0.0});
  for (int k = 0; k < 200; ++k) plant.step(0.0, kT);
  EXPECT_LT(p.r * plant.state().theta_m, -0.01);
}

// ---------------------------------------------------------------------------------------------
// Section 2: dropping the inductance (eq. 2.6 → 2.8/3.9) is right as t_e / t_m → 0.

struct OpenLoopRun {
  std::vector<double> theta_m;
  double seconds = 0.0;
};

OpenLoopRun open_loop_step(const DcMotorParams& p, DcMotorModel model, double u_m, int ticks) {
  OpenLoopRun run;
  run.theta_m.reserve(static_cast<std::size_t>(ticks));
  DcMotorPlant plant(p, model, {});
  const auto start = std::chrono::steady_clock::now();
  for (int k = 0; k < ticks; ++k) {
    plant.step(u_m, kT);
    run.theta_m.push_back(plant.state().theta_m);
  }
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return run;
}

TEST(DcMotorPlant, WithoutInductanceMatchesTheFullModelAsTeOverTmVanishes_Eq2_8) {
  // A 3 V step from rest, link horizontal, for 0.2 s: the link swings up against gravity.
  constexpr int kTicks = 200;
  const double u_m = 3.0;
  const DcMotorParams nominal;
  const OpenLoopRun simplified =
      open_loop_step(nominal, DcMotorModel::kWithoutInductance, u_m, kTicks);
  std::printf(
      "  t_e/t_m    L_m [H]     sub-steps/tick  max|Δθ_m| [rad]  full [ms]  simplified [ms]\n");
  double previous_error = std::numeric_limits<double>::infinity();
  double first_error = 0.0;
  for (const double scale : {1.0, 0.1, 0.01, 0.001}) {
    DcMotorParams p = nominal;
    p.L_m = nominal.L_m * scale;
    const OpenLoopRun full = open_loop_step(p, DcMotorModel::kWithInductance, u_m, kTicks);
    double error = 0.0;
    for (std::size_t k = 0; k < full.theta_m.size(); ++k) {
      error = std::max(error, std::abs(full.theta_m[k] - simplified.theta_m[k]));
    }
    const DcMotorPlant probe(p, DcMotorModel::kWithInductance);
    std::printf("  %-9.3g  %-10.3g  %-14u  %-15.4g  %-9.3f  %.3f\n", p.t_e() / p.t_m(), p.L_m,
                probe.substeps_for(kT), error, 1e3 * full.seconds, 1e3 * simplified.seconds);
    EXPECT_LT(error, previous_error) << "t_e/t_m " << p.t_e() / p.t_m();
    if (scale == 1.0) first_error = error;
    previous_error = error;
  }
  // The gap is the current's first-order lag, so it scales with t_e: three decades of t_e should
  // take off well over two decades of error.
  EXPECT_LT(previous_error, 1e-2 * first_error);
}

TEST(DcMotorPlant, EachIntegratorConvergesAtItsOrderToTheSameTrajectory) {
  // The simplified model (eq. 3.9), a 3 V step from rest for 0.2 s, against RK4 at 400 sub-steps.
  const DcMotorParams p;
  const auto final_angle = [&](Integrator method, std::uint32_t substeps) {
    DcMotorPlant plant(p, DcMotorModel::kWithoutInductance, {}, {method, substeps});
    for (int k = 0; k < 200; ++k) plant.step(3.0, kT);
    return plant.state().theta_m;
  };
  const double reference = final_angle(Integrator::kRk4, 400);
  struct Case {
    Integrator method;
    double order;
  };
  for (const Case c : {Case{Integrator::kExplicitEuler, 1.0}, Case{Integrator::kSemiImplicitEuler, 1.0},
                       Case{Integrator::kRk4, 4.0}}) {
    const std::uint32_t coarse_n = c.method == Integrator::kRk4 ? 1 : 4;
    const double coarse = std::abs(final_angle(c.method, coarse_n) - reference);
    const double fine = std::abs(final_angle(c.method, 2 * coarse_n) - reference);
    std::printf("  %-20s n=%u: |Δθ_m| %.3g rad, n=%u: %.3g rad, observed order %.2f\n",
                std::string(integrator_name(c.method)).c_str(), coarse_n, coarse, 2 * coarse_n,
                fine, std::log2(coarse / fine));
    EXPECT_NEAR(std::log2(coarse / fine), c.order, 0.3) << integrator_name(c.method);
  }
}

// ---------------------------------------------------------------------------------------------
// Section 5: direct torque control (eq. 5.2) with the PD law (eq. 5.5).

TEST(DirectTorqueControl, PdOnTheLinearizedDeviceReachesTheTarget_Eq5_2) {
  const DcMotorParams p;
  DcMotorPlant plant(p, DcMotorModel::kWithoutInductance, {});
  const double theta_md = 5.0;  // rad at the motor: 0.5 rad at the load
  for (int k = 0; k < 1000; ++k) {
    const DcMotorState& s = plant.state();
    // K_P = 400 1/s², K_D = 40 1/s: ω_n = 20 rad/s, ζ = 1.
    const double v = pd_acceleration(400.0, 40.0, theta_md, s.theta_m, s.omega_m);
    const double u = direct_torque_control(p, v, s.theta_m, s.omega_m);
    plant.step(voltage_from_torque_command(p, u), kT);
  }
  EXPECT_NEAR(plant.state().theta_m, theta_md, 1e-4);
  EXPECT_NEAR(plant.state().omega_m, 0.0, 1e-3);
}

// ---------------------------------------------------------------------------------------------
// Section 9: gravity compensation with a virtual torsion spring (eqs. 9.6–9.7).

struct LoopCase {
  DcMotorModel model;
  SpringDiscretization discretization;
};

class HapticLoop : public ::testing::TestWithParam<LoopCase> {};

TEST_P(HapticLoop, SettlesAtTheSpringRestAngle_Eq9_7) {
  const DcMotorParams p;
  HapticLoopConfig config;
  config.theta_m0 = 3.0;  // θ_L0 = 0.3 rad
  config.discretization = GetParam().discretization;
  // Let go 0.2 rad (load) away from the rest angle. Eq. 9.7 with τ_e = 0 is an overdamped
  // oscillator whose slow pole is ≈ r k_V / (B + K_D + r B_V) ≈ 9.8 rad/s: 3 s is 29 time
  // constants.
  DcMotorPlant plant(p, GetParam().model, {config.theta_m0 + 2.0, 0.0, 0.0});
  double max_overshoot = 0.0;
  run_haptic_loop(plant, config, 3000, kNoHand,
                  [&](std::uint64_t, const DcMotorState& s, double) {
                    max_overshoot = std::max(max_overshoot, config.theta_m0 - s.theta_m);
                  });
  EXPECT_NEAR(plant.state().theta_m, config.theta_m0, 1e-6);
  EXPECT_NEAR(plant.state().omega_m, 0.0, 1e-6);
  EXPECT_LT(max_overshoot, 1e-3);  // overdamped: no swing through the rest angle
}

// Eq. 9.7 at rest with a constant operator torque n_ez: r k_V (θ_m − θ_m0) = (r/η) τ_e.
TEST_P(HapticLoop, AConstantOperatorTorqueDeflectsTheSpringByTauOverEtaK_Eq9_7) {
  const DcMotorParams p;
  HapticLoopConfig config;
  config.theta_m0 = -2.0;
  config.discretization = GetParam().discretization;
  const double n_ez = 0.05;  // N·m at the load
  DcMotorPlant plant(p, GetParam().model, {config.theta_m0, 0.0, 0.0});
  run_haptic_loop(plant, config, 4000,
                  [&](double, double) { return ExternalWrench{{}, {0.0, 0.0, n_ez}}; },
                  kNoObserver);
  EXPECT_NEAR(plant.state().theta_m - config.theta_m0, n_ez / (p.eta * config.k_V), 1e-6);
}

INSTANTIATE_TEST_SUITE_P(
    ModelsAndDiscretizations, HapticLoop,
    ::testing::Values(LoopCase{DcMotorModel::kWithInductance, SpringDiscretization::kExactDelayed},
                      LoopCase{DcMotorModel::kWithInductance, SpringDiscretization::kEulerBackward},
                      LoopCase{DcMotorModel::kWithoutInductance,
                               SpringDiscretization::kExactDelayed},
                      LoopCase{DcMotorModel::kWithoutInductance,
                               SpringDiscretization::kEulerBackward}));

}  // namespace
}  // namespace haptic::engine
