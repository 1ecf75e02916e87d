// The shared fixed-step integrators on the undamped oscillator q̈ = −ω² q, whose exact solution is
// known: observed order of accuracy, and the energy behaviour that decides between the two Euler
// methods on a zero-damping plant.
#include "engine/core/integrator.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include <gtest/gtest.h>

namespace haptic::engine {
namespace {

constexpr double kOmega = 2.0 * 3.141592653589793 * 5.0;  // 5 Hz. Unit: rad/s.

auto oscillator() {
  return [](const StateVector<2>& x) { return StateVector<2>{x[1], -kOmega * kOmega * x[0]}; };
}

/// Largest position error over 0.4 s (two periods) from q = 1, q̇ = 0, with `substeps` steps per
/// 5 ms tick (ωh = 0.16 at one sub-step: far enough from round-off for RK4's order to show).
double error_after(Integrator method, std::uint32_t substeps) {
  StateVector<2> x{1.0, 0.0};
  const IntegrationSettings settings{method, substeps};
  double worst = 0.0;
  for (int tick = 1; tick <= 80; ++tick) {
    integrate_tick<1>(settings, x, 5e-3, oscillator());
    worst = std::max(worst, std::abs(x[0] - std::cos(kOmega * 5e-3 * tick)));
  }
  return worst;
}

double energy(const StateVector<2>& x) { return 0.5 * x[1] * x[1] + 0.5 * kOmega * kOmega * x[0] * x[0]; }

TEST(Integrator, ObservedOrdersAreOneOneAndFour) {
  struct Case {
    Integrator method;
    double order;
  };
  for (const Case c : {Case{Integrator::kExplicitEuler, 1.0}, Case{Integrator::kSemiImplicitEuler, 1.0},
                       Case{Integrator::kRk4, 4.0}}) {
    const double coarse = error_after(c.method, 4);
    const double fine = error_after(c.method, 8);
    const double observed = std::log2(coarse / fine);
    EXPECT_NEAR(observed, c.order, 0.15) << integrator_name(c.method) << ": errors " << coarse
                                         << " -> " << fine;
  }
}

TEST(Integrator, OnAnUndampedOscillatorExplicitEulerGainsEnergyAndSemiImplicitStaysBounded) {
  StateVector<2> euler{1.0, 0.0};
  StateVector<2> symplectic{1.0, 0.0};
  const double e0 = energy(euler);
  double symplectic_max = 0.0;
  for (int tick = 0; tick < 10'000; ++tick) {  // 10 s, 50 periods, one step per 1 ms tick
    integrate_tick<1>({Integrator::kExplicitEuler, 1}, euler, 1e-3, oscillator());
    integrate_tick<1>({Integrator::kSemiImplicitEuler, 1}, symplectic, 1e-3, oscillator());
    symplectic_max = std::max(symplectic_max, energy(symplectic) / e0);
  }
  // Explicit Euler multiplies the energy by (1 + (ωh)²) per step: e^{10⁴·ln(1+0.000987)} ≈ 19 000.
  EXPECT_GT(energy(euler) / e0, 1e3);
  // Symplectic Euler conserves a shadow energy within O(ωh) of the true one.
  EXPECT_LT(symplectic_max, 1.0 + 2.0 * kOmega * 1e-3);
}

TEST(Integrator, ImplicitEulerAndTheTrapezoidalRuleConvergeAtOrdersOneAndTwo) {
  for (const auto& [method, order] : {std::pair{Integrator::kImplicitEuler, 1.0},
                                      std::pair{Integrator::kTrapezoidal, 2.0}}) {
    const double coarse = error_after(method, 4);
    const double fine = error_after(method, 8);
    EXPECT_NEAR(std::log2(coarse / fine), order, 0.15)
        << integrator_name(method) << ": errors " << coarse << " -> " << fine;
  }
}

TEST(Integrator, TheImplicitMethodsStayStableWhereTheExplicitOnesBlowUp) {
  // A stiff decay ẋ = −λ x with λ h = 100: explicit Euler multiplies by −99 per step.
  const auto decay = [](const StateVector<2>& x) { return StateVector<2>{x[1], -1e5 * x[1]}; };
  StateVector<2> explicit_x{0.0, 1.0}, implicit_x{0.0, 1.0}, trapezoid_x{0.0, 1.0};
  for (int k = 0; k < 20; ++k) {
    integrate_step<1>(Integrator::kExplicitEuler, explicit_x, 1e-3, decay);
    integrate_step<1>(Integrator::kImplicitEuler, implicit_x, 1e-3, decay);
    integrate_step<1>(Integrator::kTrapezoidal, trapezoid_x, 1e-3, decay);
  }
  EXPECT_GT(std::abs(explicit_x[1]), 1e30);
  EXPECT_LT(std::abs(implicit_x[1]), 1e-30);    // L-stable: 1/(1 + λh) per step
  EXPECT_LE(std::abs(trapezoid_x[1]), 1.0);     // A-stable: |(1 − λh/2)/(1 + λh/2)| < 1
  // On the undamped oscillator the trapezoidal rule keeps the energy; implicit Euler drains it.
  StateVector<2> trapezoid{1.0, 0.0}, backward{1.0, 0.0};
  const double e0 = energy(trapezoid);
  for (int tick = 0; tick < 2000; ++tick) {
    integrate_tick<1>({Integrator::kTrapezoidal, 1}, trapezoid, 1e-3, oscillator());
    integrate_tick<1>({Integrator::kImplicitEuler, 1}, backward, 1e-3, oscillator());
  }
  EXPECT_NEAR(energy(trapezoid) / e0, 1.0, 1e-9);
  EXPECT_LT(energy(backward) / e0, 0.9);
}

TEST(Integrator, NamesRoundTripAndUnknownNamesAreRejected) {
  for (const Integrator m : {Integrator::kExplicitEuler, Integrator::kSemiImplicitEuler, Integrator::kRk4,
                             Integrator::kImplicitEuler, Integrator::kTrapezoidal}) {
    EXPECT_EQ(integrator_from_name(integrator_name(m)), m);
  }
  EXPECT_FALSE(integrator_from_name("rk5").has_value());
  EXPECT_FALSE(integrator_from_name("").has_value());
}

TEST(Integrator, ZeroSubstepsTakesOneStep) {
  StateVector<2> x{1.0, 0.0};
  integrate_tick<1>({Integrator::kExplicitEuler, 0}, x, 1e-3, oscillator());
  EXPECT_DOUBLE_EQ(x[0], 1.0);
  EXPECT_DOUBLE_EQ(x[1], -kOmega * kOmega * 1e-3);
}

}  // namespace
}  // namespace haptic::engine
