// haptic-lab's study: the runner (references, errors, stability, energy drift, validation,
// progress) and the ODE cases' physics, checked against what the schemes' theory predicts.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "lab/study.hpp"

namespace haptic::lab {
namespace {

StudyCase find_case(const std::string& name) {
  for (StudyCase& c : ode_cases(true)) {
    if (c.name == name) return c;
  }
  throw std::runtime_error("no case " + name);
}

StudyReport run_one(StudyCase c, std::vector<double> steps, std::vector<Scheme> schemes = {}, double min_cpu_s = 0.0) {
  c.steps_s = std::move(steps);
  if (!schemes.empty()) c.schemes = std::move(schemes);
  StudyOptions options;
  options.min_cpu_s = min_cpu_s;
  return run_study({c}, options);
}

const StudyResult& row(const StudyReport& report, Scheme scheme, double step, const std::string& variant = "") {
  for (const StudyResult& r : report.results) {
    if (r.scheme == scheme && std::abs(r.step_s - step) < 1e-15 && r.variant == variant) return r;
  }
  throw std::runtime_error("no row");
}

TEST(StudySchemes, NamesRoundTripAndUnknownNamesAreRefused) {
  for (const Scheme scheme : kAllSchemes) EXPECT_EQ(scheme_from_name(scheme_name(scheme)), scheme);
  EXPECT_FALSE(scheme_from_name("rk5").has_value());
  EXPECT_FALSE(as_integrator(Scheme::kExactZoh).has_value());
  EXPECT_EQ(as_integrator(Scheme::kTrapezoidal), engine::Integrator::kTrapezoidal);
}

TEST(StudyZoh, MatrixExponentialMatchesTheDampedOscillatorsClosedForm) {
  // m = 0.01, K = 1000, B = 1: σ = 50 1/s, ω_d = √(1e5 − 2500) rad/s; Φ(h)[0][0] = e^{−σh}(cos ω_d h + σ/ω_d sin ω_d h).
  const double m = 0.01, k = 1e3, b = 1.0, h = 1e-3;
  const engine::ZohStep<2> zoh = engine::exact_zoh<2>({{{0.0, 1.0}, {-k / m, -b / m}}}, {0.0, 1.0 / m}, h);
  const double sigma = b / (2 * m), wd = std::sqrt(k / m - sigma * sigma);
  EXPECT_NEAR(zoh.phi[0][0], std::exp(-sigma * h) * (std::cos(wd * h) + sigma / wd * std::sin(wd * h)), 1e-14);
  EXPECT_NEAR(zoh.phi[0][1], std::exp(-sigma * h) * std::sin(wd * h) / wd, 1e-16);
  // Γ[0] is the displacement under a unit force held from rest: (1 − Φ00)/K.
  EXPECT_NEAR(zoh.gamma[0], (1.0 - zoh.phi[0][0]) / k, 1e-15);
}

TEST(StudyOdeCases, ObservedOrdersOnTheLinearWallAreTheSchemesOrders) {
  const StudyReport report = run_one(find_case("linear_wall"), {1e-5, 1e-4, 1e-3});
  auto order = [&](Scheme s, double fine, double coarse) {
    return std::log10(row(report, s, coarse).error / row(report, s, fine).error) / std::log10(coarse / fine);
  };
  EXPECT_NEAR(order(Scheme::kExplicitEuler, 1e-5, 1e-4), 1.0, 0.15);
  EXPECT_NEAR(order(Scheme::kSemiImplicitEuler, 1e-5, 1e-4), 1.0, 0.15);
  EXPECT_NEAR(order(Scheme::kImplicitEuler, 1e-5, 1e-4), 1.0, 0.15);
  EXPECT_NEAR(order(Scheme::kTrapezoidal, 1e-5, 1e-4), 2.0, 0.2);
  EXPECT_NEAR(order(Scheme::kRk4, 1e-4, 1e-3), 4.0, 0.4);
  for (const double h : {1e-5, 1e-4, 1e-3}) {
    EXPECT_LT(row(report, Scheme::kExactZoh, h).relative_error, 1e-9) << h;  // exact for a linear part
    EXPECT_TRUE(row(report, Scheme::kExactZoh, h).stable);
  }
  ASSERT_EQ(report.references.size(), 1u);
  EXPECT_TRUE(report.references[0].exact);
  EXPECT_NEAR(report.references[0].scale, 0.005, 1e-12);  // starts 5 mm in
}

TEST(StudyOdeCases, StiffWallAtOneMillisecondSeparatesTheSchemesByTheirStabilityRegions) {
  // K = 1e5, m = 0.01: ω = 3162 rad/s. At h = 1e-3, ωh = 3.16: beyond semi-implicit Euler's 2,
  // RK4's 2.83 on the imaginary axis and explicit Euler's hB/m ... (it needs h < B/K = 1e-5).
  const StudyReport report = run_one(find_case("stiff_wall"), {1e-6, 1e-3});
  EXPECT_FALSE(row(report, Scheme::kExplicitEuler, 1e-3).stable);
  EXPECT_FALSE(row(report, Scheme::kSemiImplicitEuler, 1e-3).stable);
  EXPECT_FALSE(row(report, Scheme::kRk4, 1e-3).stable);
  EXPECT_TRUE(row(report, Scheme::kImplicitEuler, 1e-3).stable);
  EXPECT_TRUE(row(report, Scheme::kTrapezoidal, 1e-3).stable);
  EXPECT_TRUE(row(report, Scheme::kExactZoh, 1e-3).stable);
  EXPECT_TRUE(std::isinf(row(report, Scheme::kExplicitEuler, 1e-3).error));
  EXPECT_FALSE(row(report, Scheme::kExplicitEuler, 1e-3).note.empty());  // says where it stopped
  for (const Scheme s : kAllSchemes) EXPECT_TRUE(row(report, s, 1e-6).stable) << scheme_name(s);
}

TEST(StudyOdeCases, ZeroDampingEnergyDriftHasEachSchemesSign) {
  const StudyReport report = run_one(find_case("zero_damping"), {1e-4});
  EXPECT_GT(row(report, Scheme::kExplicitEuler, 1e-4).energy_drift, 0.01);   // gains energy
  EXPECT_LT(row(report, Scheme::kImplicitEuler, 1e-4).energy_drift, -0.01);  // loses it
  EXPECT_LT(std::abs(row(report, Scheme::kTrapezoidal, 1e-4).energy_drift), 1e-9);  // keeps it
  EXPECT_LT(std::abs(row(report, Scheme::kExactZoh, 1e-4).energy_drift), 1e-9);
  EXPECT_LT(std::abs(row(report, Scheme::kSemiImplicitEuler, 1e-4).energy_drift), 0.06);  // bounded
}

TEST(StudyOdeCases, NanIsAResultUnguardedAndHarmlessThroughTheForceGuard) {
  const StudyReport raw = run_one(find_case("nan_unguarded"), {1e-4});
  for (const StudyResult& r : raw.results) {
    EXPECT_FALSE(r.stable) << scheme_name(r.scheme);
    EXPECT_NE(r.note.find("non-finite"), std::string::npos) << r.note;
  }
  const StudyReport guarded = run_one(find_case("nan_guarded"), {1e-4});
  for (const StudyResult& r : guarded.results) {
    EXPECT_TRUE(r.stable) << scheme_name(r.scheme);
    EXPECT_NE(r.note.find("100 force-fault ticks"), std::string::npos) << r.note;  // 10 ms at 1e-4 s
  }
  EXPECT_LT(row(guarded, Scheme::kExactZoh, 1e-4).relative_error, 1e-9);
}

TEST(StudyOdeCases, ForceStepOfAThousandNewtonsIsFollowedExactlyByTheZohScheme) {
  const StudyReport report = run_one(find_case("force_step"), {1e-4, 1e-3});
  EXPECT_NEAR(report.references[0].scale, 2 * 1e3 / 1e4, 0.05);  // overshoot towards 2 F/K
  EXPECT_LT(row(report, Scheme::kExactZoh, 1e-3).relative_error, 1e-9);
  EXPECT_LT(row(report, Scheme::kRk4, 1e-4).relative_error, 1e-6);
}

TEST(StudyOdeCases, ViscousSurfaceFollowsEquation7Point1) {
  // 000 eq. 7.1 under a 1 N push from rest: v → F/B_V = 0.25 m/s with τ = m_V/B_V = 0.05 s.
  const StudyReport report = run_one(find_case("viscous_surface"), {1e-3});
  const double t = 0.2, tau = 0.05, v_inf = 0.25;
  EXPECT_NEAR(report.references[0].scale, v_inf * t - v_inf * tau * (1.0 - std::exp(-t / tau)), 1e-12);
  EXPECT_LT(row(report, Scheme::kRk4, 1e-3).relative_error, 1e-9);
}

TEST(StudyOdeCases, FrictionReferenceHasConvergedAndTheModelsDiffer) {
  const StudyReport report = run_one(find_case("joint_friction_models"), {1e-4}, {Scheme::kRk4});
  ASSERT_EQ(report.references.size(), 1u);
  EXPECT_FALSE(report.references[0].exact);
  EXPECT_LT(report.references[0].convergence, 1e-3 * report.references[0].scale);
  const double karnopp = row(report, Scheme::kRk4, 1e-4, "karnopp").error;
  const double viscous = row(report, Scheme::kRk4, 1e-4, "viscous_only").error;
  EXPECT_GT(viscous, 10.0 * karnopp);  // dropping Coulomb friction costs far more than the step
}

TEST(StudyRunner, BadCasesAreRefusedBeforeAnyWorkNamingTheCase) {
  StudyCase c = find_case("linear_wall");
  int runs = 0;
  auto simulate = c.simulate;
  c.simulate = [&runs, simulate](Scheme s, double h, const std::string& v) {
    ++runs;
    return simulate(s, h, v);
  };
  auto expect_refused = [&](StudyCase bad, const std::string& words) {
    try {
      run_study({find_case("viscous_surface"), bad}, {});
      FAIL() << "accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  StudyCase bad = c;
  bad.steps_s = {1e-3, -1e-3};
  expect_refused(bad, "linear_wall\": step must be finite and > 0 s, got -0.001");
  bad.steps_s = {3e-3};
  expect_refused(bad, "step 0.003 s does not divide the output period 0.01 s");
  bad.steps_s = {1e-8};
  expect_refused(bad, "step 1e-08 s is below the study's 1e-07 s");
  bad.steps_s = {1e-3};
  bad.check_step = [](double) { return std::string("not this one"); };
  expect_refused(bad, "linear_wall\": not this one");
  bad = c;
  bad.schemes.clear();
  expect_refused(bad, "has no schemes");
  bad = c;
  bad.duration_s = 0.105;
  expect_refused(bad, "must be a positive multiple of the output period");
  EXPECT_EQ(runs, 0);
}

TEST(StudyRunner, ProgressCountsEveryRunAndReferenceAndThreadsGiveTheSameRows) {
  StudyCase c = find_case("linear_wall");
  c.steps_s = {1e-4, 1e-3};
  std::size_t calls = 0, last_done = 0, last_total = 0;
  StudyOptions options;
  options.min_cpu_s = 0.0;
  options.threads = 2;
  options.progress = [&](std::size_t done, std::size_t total, const std::string&) {
    ++calls;
    last_done = done;
    last_total = total;
  };
  const StudyReport two = run_study({c}, options);
  EXPECT_EQ(last_total, 1u + 6u * 2u);
  EXPECT_EQ(calls, last_total);
  EXPECT_EQ(last_done, last_total);
  options.threads = 1;
  const StudyReport one = run_study({c}, options);
  ASSERT_EQ(one.results.size(), two.results.size());
  for (std::size_t i = 0; i < one.results.size(); ++i) {
    EXPECT_EQ(one.results[i].error, two.results[i].error);
    EXPECT_GT(two.results[i].cpu_s_per_sim_s, 0.0);
  }
  std::ostringstream csv;
  write_study_csv({c}, one, csv);
  EXPECT_EQ(csv.str().rfind("case,group,variant,scheme,step_s,error,relative_error,cpu_s_per_sim_s,stable,energy_drift,note\n", 0), 0u);
  EXPECT_NE(csv.str().find("linear_wall,schemes,,exact_zoh,0.001,"), std::string::npos) << csv.str();
}

}  // namespace
}  // namespace haptic::lab

namespace haptic::lab {
namespace {

TEST(StudyReport, SummaryGivesTheLargestStableStepAndTheCheapestAccurateRun) {
  StudyCase c = find_case("stiff_wall");
  // The cheapest run is chosen by CPU time: each run repeated for 20 ms of it, so that one
  // preemption on a loaded host cannot make the 1 ms run look dearer than the 0.1 ms one.
  const StudyReport report = run_one(c, {1e-6, 1e-5, 1e-4, 1e-3}, {}, 0.02);
  std::ostringstream md;
  write_study_summary({c}, report, md);
  // RK4 is stable up to 1e-4 s (ωh = 0.32) and not at 1e-3 s (3.16 > 2.83); exact ZOH at every step.
  EXPECT_NE(md.str().find("| stiff_wall | — | rk4 | 0.0001 | "), std::string::npos) << md.str();
  EXPECT_NE(md.str().find("| stiff_wall | — | exact_zoh | ≥ 0.001 | 0.001 | "), std::string::npos) << md.str();
  EXPECT_NE(md.str().find("| stiff_wall | — | implicit_euler | ≥ 0.001 | not reached | — |"), std::string::npos)
      << md.str();  // first order: 1e-3 relative needs a finer step than 1e-6 s
}

}  // namespace
}  // namespace haptic::lab

namespace haptic::lab {
namespace {

TEST(StudyOdeCases, ImpedanceLawsAtTheTickPeriodAreFirstOrderAndFailAtCoarseRates) {
  const StudyReport report = run_one(find_case("sampled_wall_laws"), {1e-5, 1e-4, 1e-3, 1e-2});
  for (const std::string law : {"velocity", "backward_difference", "exact_zoh", "tustin"}) {
    const double fine = row(report, Scheme::kExactZoh, 1e-5, law).error;
    const double coarse = row(report, Scheme::kExactZoh, 1e-4, law).error;
    EXPECT_NEAR(coarse / fine, 10.0, 1.0) << law;  // the held force lags by T/2: first order in T
    EXPECT_TRUE(row(report, Scheme::kExactZoh, 1e-3, law).stable) << law;
    EXPECT_FALSE(row(report, Scheme::kExactZoh, 1e-2, law).stable) << law;  // ωT = 3.2
  }
  // The ZOH takes away damping (≈ K T / 2 = 0.5 of the 1.022 N·s/m at 1 ms), so the rendered wall
  // rings longer than the continuous one: a large trajectory error while still stable.
  EXPECT_GT(row(report, Scheme::kExactZoh, 1e-3, "backward_difference").relative_error, 0.1);
}

TEST(StudyOdeCases, OrientationSpringLawsAreFirstOrderAndRingUpWhereTheAnalysisSays) {
  const StudyReport report = run_one(find_case("orientation_spring_laws"), {1e-5, 1e-4, 1e-3, 1e-2});
  for (const std::string law : {"velocity", "backward_difference", "exact_zoh", "tustin"}) {
    const double fine = row(report, Scheme::kExactZoh, 1e-5, law).error;
    const double coarse = row(report, Scheme::kExactZoh, 1e-4, law).error;
    EXPECT_NEAR(coarse / fine, 10.0, 1.0) << law;  // the held torque lags by T/2: first order in T
    EXPECT_TRUE(row(report, Scheme::kExactZoh, 1e-3, law).stable) << law;
    // At 10 ms k = 0.3 N·m/rad is past every law's largest stable stiffness on this handle
    // (0.10–0.14 N·m/rad by the sampled analysis): the handle rings up out of its bound.
    EXPECT_FALSE(row(report, Scheme::kExactZoh, 1e-2, law).stable) << law;
  }
  // 000 eq. 8.12's one-sample delay costs the exact-ZOH law twice the others' error, as on a wall.
  EXPECT_NEAR(row(report, Scheme::kExactZoh, 1e-4, "exact_zoh").error /
                  row(report, Scheme::kExactZoh, 1e-4, "backward_difference").error,
              2.0, 0.1);
}

TEST(StudyOdeCases, KhatibFieldGradientByCentralDifferencesHasItsOwnErrorFloor) {
  const StudyReport report = run_one(find_case("khatib_field"), {1e-5, 1e-4}, {Scheme::kRk4, Scheme::kTrapezoidal});
  // Analytic gradient: RK4 converges far below either difference step's floor.
  EXPECT_LT(row(report, Scheme::kRk4, 1e-5, "analytic").relative_error, 1e-8);
  // Step 1e-6 m: rounding (ε U / h) leaves ≈ 2.5e-7 of the motion; step 1e-3 m: the O(h²) error of
  // eq. 5.7's differences near the surface, ≈ 20 %, whatever the time step.
  const double fine_floor = row(report, Scheme::kRk4, 1e-5, "central_1e-6").relative_error;
  EXPECT_GT(fine_floor, 1e-8);
  EXPECT_LT(fine_floor, 1e-4);
  EXPECT_GT(row(report, Scheme::kRk4, 1e-5, "central_1e-3").relative_error, 0.05);
  EXPECT_NEAR(row(report, Scheme::kRk4, 1e-4, "central_1e-3").error, row(report, Scheme::kRk4, 1e-5, "central_1e-3").error,
              1e-3 * row(report, Scheme::kRk4, 1e-5, "central_1e-3").error);
  // Nothing dissipates: the trapezoidal rule keeps the energy to 1e-6 at 1e-4 s.
  EXPECT_LT(std::abs(row(report, Scheme::kTrapezoidal, 1e-4, "analytic").energy_drift), 1e-6);
}

}  // namespace
}  // namespace haptic::lab

namespace haptic::lab {
namespace {

TEST(StudyOdeCases, TheWholeServerRendersTheVelocityLawsDifferenceEquationAtEveryRate) {
  // Both cases are the same linear sampled loop (001's device, K 1e3, B 1 on the measured
  // velocity, the force held over a tick), one excited by an initial displacement in the lab's
  // model, the other by a hand step through hapticd's tick: the relative energy error, which
  // does not depend on the excitation's size, must agree at every tick period.
  const StudyReport lab = run_one(find_case("sampled_wall_laws"), {1e-4, 1e-3, 1e-2});
  const StudyReport server = run_one(find_case("server_spring_rates"), {1e-4, 1e-3, 1e-2});
  for (const double T : {1e-4, 1e-3}) {
    const StudyResult& s = row(server, Scheme::kExactZoh, T);
    EXPECT_TRUE(s.stable) << T;
    EXPECT_NEAR(s.energy_drift, row(lab, Scheme::kExactZoh, T, "velocity").energy_drift, 1e-6 * s.energy_drift) << T;
  }
  EXPECT_FALSE(row(server, Scheme::kExactZoh, 1e-2).stable);  // ωT = 3.2: the rendered spring rings up
  EXPECT_EQ(row(server, Scheme::kExactZoh, 1e-2).note.find("non-finite"), std::string::npos)
      << "the force guard keeps it finite";
}

TEST(StudyRunner, ARunWithAPoleAt1Point001IsUnstableThoughItNeverGrowsTenfold) {
  // x = p^(t/h) cos(ω t) sampled every 10 ms over 0.5 s, its energy ½ x-amplitude²: at h = 1 ms a
  // pole p = 1.001 grows 1.65× over the run, which the size criterion (10× the reference) passes.
  constexpr double kOmega = 300.0;
  const auto trajectory = [](double pole, double step) {
    Trajectory t;
    for (int k = 0; k <= 50; ++k) {
      const double time = 0.01 * k;
      const double amplitude = std::pow(pole, time / step);
      t.samples.push_back({amplitude * std::cos(kOmega * time), 0.0, 0.0});
      t.energy.push_back(0.5 * amplitude * amplitude);
    }
    return t;
  };
  StudyCase c;
  c.name = "pole_1_001";
  c.title = "an oscillation with a closed-loop pole at 1.001 per step";
  c.source = "this test";
  c.observable = "x";
  c.schemes = {Scheme::kExactZoh};
  c.steps_s = {1e-3};
  c.variants = {"steady", "growing"};
  c.exact = [trajectory] { return trajectory(1.0, 1e-3); };
  c.simulate = [trajectory](Scheme, double step, const std::string& variant) {
    return trajectory(variant == "growing" ? 1.001 : 1.0, step);
  };
  StudyOptions options;
  options.min_cpu_s = 0.0;
  const StudyReport report = run_study({c}, options);
  ASSERT_EQ(report.results.size(), 2u);
  for (const StudyResult& r : report.results) {
    if (r.variant == "growing") {
      EXPECT_FALSE(r.stable) << r.note;
      EXPECT_NE(r.note.find("rings up"), std::string::npos) << r.note;
    } else {
      EXPECT_TRUE(r.stable) << r.note;
    }
  }
}

}  // namespace
}  // namespace haptic::lab
