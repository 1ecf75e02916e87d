// A device axis identified from a multisine (engine/analysis/system_identification): an exact
// mass-damper with Coulomb friction, a constant load, extra ticks of delay, noise and an encoder's
// quantization, driven through a zero-order hold at 1 kHz as a device is. Each parameter comes
// back within a stated tolerance of the truth, inside its own 95 % interval, and what cannot be
// fitted is refused saying why.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <numbers>
#include <optional>
#include <random>
#include <vector>

#include "engine/analysis/system_identification.hpp"

namespace haptic::engine {
namespace {

struct Axis {
  double mass = 0.1;       // kg
  double damping = 2.0;    // N·s/m
  double coulomb = 0.0;    // N
  double load = 0.0;       // N, constant, along +x
  std::size_t delay_ticks = 0;  // beyond the hold's
  double noise_m = 0.0;    // Gaussian, rms
  double quantum_m = 0.0;  // 0: none
  double lag_s = 0.0;      // the applied force's first-order lag behind the command; 0: none
  /// Coulomb friction that holds the axis still while the force is within it (stick and slip),
  /// in place of the smooth law. Needs damping > 0.
  bool stick = false;
};

/// One sub-step h of the mass-damper under `drive` (N, held) with Coulomb friction that holds it
/// at rest while |drive| <= c and stops it where its velocity would cross zero: exact.
void step_with_stick(const Axis& axis, double drive, double h, double& x, double& v) {
  if (v == 0.0 && std::abs(drive) <= axis.coulomb) return;  // held
  const double direction = v != 0.0 ? (v > 0.0 ? 1.0 : -1.0) : (drive > 0.0 ? 1.0 : -1.0);
  const double terminal = (drive - axis.coulomb * direction) / axis.damping;
  const double time_constant = axis.mass / axis.damping;
  double duration = h;
  const double after = terminal + (v - terminal) * std::exp(-h / time_constant);
  if (after * direction < 0.0) duration = time_constant * std::log((v - terminal) / -terminal);  // v(t) = 0
  x += terminal * duration + (v - terminal) * time_constant * (1.0 - std::exp(-duration / time_constant));
  v = duration < h ? 0.0 : after;
}

struct Recording {
  std::vector<double> force, position;
};

/// The axis driven by `excitation` through a zero-order hold: the command of tick i acts over
/// [iT, (i+1)T) after `delay_ticks` more ticks; position[i] is the reading at tick i. Solved
/// exactly over 50 sub-steps a tick; friction as c tanh(v / 0.1 mm/s) (a smooth Coulomb law).
Recording simulate(const Axis& axis, const Multisine& excitation, unsigned seed = 7) {
  const double period = excitation.params.sample_period_s;
  const auto ticks = static_cast<std::size_t>(std::llround(excitation.duration_s() / period)) + 1;
  std::mt19937_64 random(seed);
  std::normal_distribution<double> noise(0.0, axis.noise_m > 0.0 ? axis.noise_m : 1.0);
  std::deque<double> pipeline(axis.delay_ticks, 0.0);
  double x = 0.0, v = 0.0;
  double lagged = 0.0;  // the force through the lag. Unit: N.
  Recording run;
  const int substeps = 50;
  for (std::size_t i = 0; i < ticks; ++i) {
    double reading = x + (axis.noise_m > 0.0 ? noise(random) : 0.0);
    if (axis.quantum_m > 0.0) reading = axis.quantum_m * std::round(reading / axis.quantum_m);
    run.position.push_back(reading);
    const double command = excitation.force_at_tick(i);
    run.force.push_back(command);
    pipeline.push_back(command);
    const double applied = pipeline.front();
    pipeline.pop_front();
    // The mass-damper's exact solution under a force held over each sub-step (the friction's
    // held too: exact for a linear axis, first order in the sub-step for friction).
    const double h = period / substeps;
    const double decay = std::exp(-axis.damping * h / axis.mass);
    for (int s = 0; s < substeps; ++s) {
      // The lag's exact step under the held command (the mass then sees its value held over the
      // sub-step: first order in the sub-step, 20 µs against 8.8 ms).
      lagged = axis.lag_s > 0.0 ? applied + (lagged - applied) * std::exp(-h / axis.lag_s) : applied;
      if (axis.stick) {
        step_with_stick(axis, lagged + axis.load, h, x, v);
        continue;
      }
      const double friction = axis.coulomb * std::tanh(v / 1e-4);
      const double terminal = (lagged - friction + axis.load) / axis.damping;  // v as t → ∞
      x += terminal * h + (v - terminal) * (axis.mass / axis.damping) * (1.0 - decay);
      v = terminal + (v - terminal) * decay;
    }
  }
  return run;
}

/// `axis` simulated under `m` and identified; the test fails (and nothing comes back) when it
/// cannot be.
std::optional<AxisIdentification> simulate_and_identify(const Axis& axis, const Multisine& m, unsigned seed = 7) {
  const Recording run = simulate(axis, m, seed);
  std::string why;
  std::optional<AxisIdentification> id = identify_axis(m, run.force, run.position, why);
  EXPECT_TRUE(id) << why;
  return id;
}

Multisine excitation(double amplitude = 1.0, std::size_t periods = 8) {
  MultisineParams params;
  params.amplitude_n = amplitude;
  params.periods = periods;
  std::string why;
  const auto m = design_multisine(params, why);
  EXPECT_TRUE(m) << why;
  return *m;
}

TEST(SystemIdentification, TheMultisineIsPeriodicRampedAndBoundedByItsAmplitude) {
  const Multisine m = excitation(2.0);
  EXPECT_GE(m.harmonics.size(), 10u);
  EXPECT_EQ(m.force_at_tick(0), 0.0);  // the ramp starts at zero
  double peak = 0.0;
  const std::size_t n = m.params.samples_per_period, begin = m.fit_begin_tick();
  for (std::size_t i = 0; i < n; ++i) {
    peak = std::max(peak, std::abs(m.force_at_tick(begin + i)));
    EXPECT_NEAR(m.force_at_tick(begin + i), m.force_at_tick(begin + i + n), 1e-12);  // periodic
  }
  EXPECT_NEAR(peak, 2.0, 1e-9);
  const auto end = static_cast<std::size_t>(std::llround(m.duration_s() / m.params.sample_period_s));
  EXPECT_EQ(m.force_at_tick(end), 0.0);
  EXPECT_LT(std::abs(m.force_at_tick(end - 1)), 1e-3);  // ramped out
}

TEST(SystemIdentification, AnExactMassDamperIsRecoveredWithTheHoldsHalfTickOfDelay) {
  const Axis axis;
  const auto id = simulate_and_identify(axis, excitation());
  ASSERT_TRUE(id);
  EXPECT_NEAR(id->mass.value, axis.mass, 0.002 * axis.mass);
  EXPECT_NEAR(id->damping.value, axis.damping, 0.005 * axis.damping);
  EXPECT_NEAR(id->coulomb.value, 0.0, 1e-3);
  // The zero-order hold delays the force by half a tick on average.
  EXPECT_NEAR(id->delay.value, 0.5e-3, 0.05e-3);
  EXPECT_LT(id->relative_residual, 1e-3);
  EXPECT_LT(id->noise_rms_m, 1e-9);
  ASSERT_FALSE(id->response.empty());
  for (const FrequencyPoint& p : id->response) EXPECT_LT(std::abs(p.measured / p.model - 1.0), 0.01) << p.frequency_hz;
}

/// The estimate within `tolerance` of the truth, and its 95 % interval not empty.
void expect_near(const Estimate& e, double truth, double tolerance, const char* name) {
  EXPECT_NEAR(e.value, truth, tolerance) << name;
  EXPECT_GT(e.half_width_95, 0.0) << name;
}

/// The same, and the truth inside the 95 % interval: where (1) is the system's own law, the
/// interval accounts for what the noise does.
void expect_covered(const Estimate& e, double truth, double tolerance, const char* name) {
  expect_near(e, truth, tolerance, name);
  EXPECT_LE(std::abs(e.value - truth), e.half_width_95)
      << name << ": the truth " << truth << " is outside " << e.value << " ± " << e.half_width_95;
}

TEST(SystemIdentification, DelayNoiseAndAnEncoderOnALinearAxisAreRecoveredInsideTheirIntervals) {
  Axis axis;
  axis.delay_ticks = 2;
  axis.noise_m = 2e-6;
  axis.quantum_m = 1e-6;
  const auto id = simulate_and_identify(axis, excitation());
  ASSERT_TRUE(id);
  expect_covered(id->mass, axis.mass, 0.01 * axis.mass, "mass");
  expect_covered(id->damping, axis.damping, 0.02 * axis.damping, "damping");
  expect_covered(id->delay, 2.5e-3, 0.1e-3, "delay");  // two ticks and the hold's half
  ASSERT_TRUE(id->quantization_m);
  EXPECT_NEAR(*id->quantization_m, axis.quantum_m, 1e-12);
  // Noise and quantization together: √(σ² + q²/12).
  EXPECT_NEAR(id->noise_rms_m, std::sqrt(4e-12 + 1e-12 / 12.0), 0.2e-6);
}

TEST(SystemIdentification, AnActuatorsFirstOrderLagIsFoundBesideTheDelayWhereAskedFor) {
  // 004's motors: the force follows the command with an 8.8 ms time constant. Fitted as a pure
  // delay the lag's roll-off reads as mass; fitted with the lag, the axis is its own.
  Axis axis;
  axis.lag_s = 8.8e-3;
  axis.delay_ticks = 1;
  const Multisine m = excitation();
  const Recording run = simulate(axis, m);
  std::string why;
  const auto delay_only = identify_axis(m, run.force, run.position, why);
  ASSERT_TRUE(delay_only) << why;
  EXPECT_GT(std::abs(delay_only->mass.value - axis.mass), 0.2 * axis.mass) << "a lag is no delay";
  EXPECT_EQ(delay_only->lag.value, 0.0);
  const auto with_lag = identify_axis(m, run.force, run.position, why, -1.0, 0.03);
  ASSERT_TRUE(with_lag) << why;
  expect_near(with_lag->mass, axis.mass, 0.01 * axis.mass, "mass");
  expect_near(with_lag->damping, axis.damping, 0.02 * axis.damping, "damping");
  expect_near(with_lag->lag, axis.lag_s, 0.02 * axis.lag_s, "lag");
  EXPECT_NEAR(with_lag->delay.value, 1.5e-3, 0.1e-3) << "the tick and the hold's half";
  EXPECT_LT(with_lag->relative_residual, 0.01);
  std::printf("delay only: m %.4g b %.4g tau %.3g ms; with the lag: m %.4g b %.4g tau %.3g ms lag %.4g ms\n",
              delay_only->mass.value, delay_only->damping.value, delay_only->delay.value * 1e3, with_lag->mass.value,
              with_lag->damping.value, with_lag->delay.value * 1e3, with_lag->lag.value * 1e3);
  for (const FrequencyPoint& p : with_lag->response) {
    EXPECT_LT(std::abs(p.measured / p.model - 1.0), 0.02) << p.frequency_hz;
  }
  // A lag's bound that is no number is refused.
  EXPECT_FALSE(identify_axis(m, run.force, run.position, why, -1.0, std::nan("")));
  EXPECT_NE(why.find("lag"), std::string::npos) << why;
}

TEST(SystemIdentification, CoulombFrictionAndALoadAreToldApartFromMassAndDamping) {
  Axis axis;
  axis.coulomb = 0.1;
  axis.load = 0.05;
  axis.delay_ticks = 2;
  axis.noise_m = 1e-6;
  axis.quantum_m = 1e-6;
  const auto id = simulate_and_identify(axis, excitation());
  ASSERT_TRUE(id);
  // Friction is (1)'s only nonlinear term, and its reversals are read from a band-limited velocity:
  // a bias of about 1 % remains, beyond what the noise explains, and shows in the residual.
  expect_near(id->mass, axis.mass, 0.02 * axis.mass, "mass");
  expect_near(id->damping, axis.damping, 0.02 * axis.damping, "damping");
  expect_near(id->coulomb, axis.coulomb, 0.03 * axis.coulomb, "Coulomb friction");
  // The load pushes +, so the command needs f0 = −load more: moving + takes c − load, moving −
  // c + load.
  expect_near(id->offset, -axis.load, 0.002, "offset");
  EXPECT_NEAR(id->coulomb_positive, axis.coulomb - axis.load, 0.005);
  EXPECT_NEAR(id->coulomb_negative, axis.coulomb + axis.load, 0.005);
  expect_near(id->delay, 2.5e-3, 0.2e-3, "delay");
  EXPECT_LT(id->relative_residual, 0.05);
  std::printf("  identified: m %.5f ± %.5f kg, b %.4f ± %.4f N·s/m, c %.4f ± %.4f N, f0 %.4f N, tau %.3f ± %.3f ms, "
              "noise %.3g m, residual %.3g\n",
              id->mass.value, id->mass.half_width_95, id->damping.value, id->damping.half_width_95, id->coulomb.value,
              id->coulomb.half_width_95, id->offset.value, id->delay.value * 1e3, id->delay.half_width_95 * 1e3,
              id->noise_rms_m, id->relative_residual);
}

TEST(SystemIdentification, MorePeriodsNarrowTheIntervals) {
  Axis axis;
  axis.noise_m = 5e-6;
  double previous = 0.0;
  for (const std::size_t periods : {4u, 16u}) {
    const auto id = simulate_and_identify(axis, excitation(1.0, periods), 11);
    ASSERT_TRUE(id);
    if (previous > 0.0) {
      EXPECT_LT(id->mass.half_width_95, previous);
    }
    previous = id->mass.half_width_95;
  }
}

TEST(SystemIdentification, WhatCannotBeFittedIsRefusedSayingWhy) {
  std::string why;
  MultisineParams bad;
  bad.periods = 2;
  EXPECT_FALSE(design_multisine(bad, why));
  EXPECT_NE(why.find("periods >= 4"), std::string::npos) << why;
  MultisineParams narrow;
  narrow.f_min_hz = 10.0;
  narrow.f_max_hz = 10.5;
  EXPECT_FALSE(design_multisine(narrow, why));
  EXPECT_NE(why.find("fewer than three harmonics"), std::string::npos) << why;

  const Multisine m = excitation();
  std::vector<double> short_run(100, 0.0);
  EXPECT_FALSE(identify_axis(m, short_run, short_run, why));
  EXPECT_NE(why.find("ticks recorded"), std::string::npos) << why;
  Recording run = simulate(Axis{}, m);
  run.position[m.fit_begin_tick() + 5] = std::nan("");
  EXPECT_FALSE(identify_axis(m, run.force, run.position, why));
  EXPECT_NE(why.find("not finite"), std::string::npos) << why;
  std::vector<double> still(run.position.size(), 0.01);
  EXPECT_FALSE(identify_axis(m, run.force, still, why));
  EXPECT_NE(why.find("did not move"), std::string::npos) << why;
}

TEST(SystemIdentification, ALatticeIsFoundOnlyWherePositionsLieOnOne) {
  EXPECT_NEAR(*lattice_step(std::vector<double>{0.001, 0.004, 0.002, 0.007}), 0.001, 1e-15);
  EXPECT_FALSE(lattice_step(std::vector<double>{0.001, 0.0025, 0.0043}));
  EXPECT_FALSE(lattice_step(std::vector<double>{0.5, 0.5}));
}

TEST(SystemIdentification, ALatticeWhoseStepChangesSlowlyIsFoundAsANonlinearMapOfCountsReadsIt) {
  // 003's five-bar along x: its axial joint's counts (π/6000 rad) through x = 0.6 − 0.3 sin q,
  // the step 157 µm at home and 6 % less at q = ±0.35 rad (±0.1 m); the other joints' counts
  // move each reading by a few tenths of a micrometre.
  const double count = std::numbers::pi / 6000.0;
  std::vector<double> readings;
  for (int n = -670; n <= 670; ++n) {
    const double x = 0.6 - 0.3 * std::sin(n * count);
    readings.push_back(x);
    if (n % 3 == 0) readings.push_back(x + 3e-7);
  }
  // The step found is the median of the steps seen: the one at |q| = 335 counts.
  const double median_step = 0.3 * count * std::cos(335 * count);
  const std::optional<double> step = lattice_step(readings);
  ASSERT_TRUE(step);
  EXPECT_NEAR(*step, median_step, 0.005 * median_step);
  // Counts skipped (the tool went past them) are whole steps; a reading off the lattice is none.
  std::sort(readings.begin(), readings.end());
  for (int i = 0; i < 5; ++i) readings.erase(readings.begin() + 300);
  EXPECT_NEAR(lattice_step(readings).value_or(0.0), median_step, 0.005 * median_step);
  readings.push_back(readings.back() + 0.5 * 0.3 * count);
  EXPECT_FALSE(lattice_step(readings));
  readings.back() = readings[readings.size() - 2] + 10.5 * 0.3 * count;  // far, and off it too
  EXPECT_FALSE(lattice_step(readings));
  // Noise is no lattice, whatever its draw, nor are steps that change by more than 5 % from one
  // to the next.
  for (std::uint64_t seed = 1; seed <= 50; ++seed) {
    std::mt19937_64 random(seed);
    std::normal_distribution<double> noise(0.0, 1.0);
    std::vector<double> noisy;
    for (int i = 0; i < 2000; ++i) noisy.push_back(noise(random));
    EXPECT_FALSE(lattice_step(noisy)) << "seed " << seed;
  }
  EXPECT_FALSE(lattice_step(std::vector<double>{0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.2, 10.2}));
  // Readings a fiftieth of a step apart that chain wider than a twentieth are no one count.
  EXPECT_FALSE(lattice_step(std::vector<double>{0.0, 0.015, 0.03, 0.045, 0.06, 1.06, 2.06, 3.06, 4.06, 5.06, 6.06,
                                                7.06, 8.06}));
  EXPECT_TRUE(lattice_step(std::vector<double>{0.0, 0.015, 0.03, 1.03, 2.03, 3.03, 4.03, 5.03, 6.03, 7.03, 8.03}));
  // Fewer than eight steps are too few to tell from chance.
  EXPECT_FALSE(lattice_step(std::vector<double>{0.0, 0.015, 0.03, 1.03, 2.03, 3.03, 4.03, 5.03, 6.03, 7.03}));
  // Twenty gaps, one of them 15 steps: the scale is not the widest gap's.
  std::vector<double> sparse{0.0, 0.015};
  for (int n = 1; n <= 18; ++n) sparse.push_back(0.015 + n);
  sparse.push_back(sparse.back() + 15.0);
  const std::optional<double> sparse_step = lattice_step(sparse);
  ASSERT_TRUE(sparse_step);
  EXPECT_NEAR(*sparse_step, 1.0, 1e-9);
}

TEST(SystemIdentification, AnAxisThatFrictionHoldsStillThroughPartOfEachPeriodIsFittedWhereItMoves) {
  // A light axis behind a motor's lag with friction that stops it at most reversals (a gimbal of
  // 004's joystick: 0.05 kg, 1 N, 8.8 ms): stuck, it is no mass-damper, and the fit at the
  // harmonics, which takes sgn ẋ for the friction throughout, misses the mass; fitted in time
  // over the samples where it moved, (1) holds there and the mass and damping come back.
  Axis axis;
  axis.mass = 0.05;
  axis.damping = 0.1;
  axis.coulomb = 1.0;
  axis.stick = true;
  axis.lag_s = 8.8e-3;
  axis.noise_m = 2e-6;
  axis.quantum_m = 10e-6;
  MultisineParams params;
  params.amplitude_n = 4.0;
  params.f_min_hz = 5.0;
  params.f_max_hz = 50.0;
  params.max_harmonics = 12;
  params.periods = 6;
  std::string why;
  const auto m = design_multisine(params, why);
  ASSERT_TRUE(m) << why;
  const Recording run = simulate(axis, *m);
  std::size_t still = 0;
  for (std::size_t i = m->fit_begin_tick() + 1; i < m->fit_begin_tick() + m->fit_ticks(); ++i) {
    still += run.position[i] == run.position[i - 1];
  }
  const double still_share = static_cast<double>(still) / static_cast<double>(m->fit_ticks());
  std::printf("stuck: %.0f %% of the fitted ticks\n", 100.0 * still_share);

  const auto harmonics = identify_axis(*m, run.force, run.position, why, -1.0, 0.02);
  ASSERT_TRUE(harmonics) << why;
  const auto moving = identify_axis(*m, run.force, run.position, why, -1.0, 0.02, FitMethod::kMovingStretches);
  ASSERT_TRUE(moving) << why;
  std::printf("harmonics: m %.4f b %.4f c %.3f lag %.2f ms delay %.2f ms residual %.3f\n", harmonics->mass.value,
              harmonics->damping.value, harmonics->coulomb.value, harmonics->lag.value * 1e3,
              harmonics->delay.value * 1e3, harmonics->relative_residual);
  std::printf("moving (%.0f %% of ticks): m %.4f ± %.4f b %.4f ± %.4f c %.3f ± %.3f lag %.2f ms delay %.2f ms "
              "residual %.3f\n",
              100.0 * moving->moving_fraction, moving->mass.value, moving->mass.half_width_95, moving->damping.value,
              moving->damping.half_width_95, moving->coulomb.value, moving->coulomb.half_width_95,
              moving->lag.value * 1e3, moving->delay.value * 1e3, moving->relative_residual);
  EXPECT_EQ(moving->method, FitMethod::kMovingStretches);
  EXPECT_LT(moving->moving_fraction, 0.9);
  EXPECT_GT(std::abs(harmonics->mass.value / axis.mass - 1.0), 0.1);  // what the method is for
  EXPECT_NEAR(moving->mass.value, axis.mass, 0.03 * axis.mass);
  EXPECT_NEAR(moving->damping.value, axis.damping, 0.05 * axis.damping);
  EXPECT_NEAR(moving->coulomb.value, axis.coulomb, 0.05 * axis.coulomb);
  EXPECT_NEAR(moving->lag.value, axis.lag_s, 0.1 * axis.lag_s);
  EXPECT_NEAR(moving->delay.value, 0.5e-3, 0.2e-3);

  // Pushed with less than its friction it never moves, and the fit in time says so.
  params.amplitude_n = 0.5;
  const auto weak = design_multisine(params, why);
  ASSERT_TRUE(weak) << why;
  const Recording held = simulate(axis, *weak);
  EXPECT_FALSE(identify_axis(*weak, held.force, held.position, why, -1.0, 0.02, FitMethod::kMovingStretches));
  EXPECT_NE(why.find("friction held it"), std::string::npos) << why;
}

}  // namespace
}  // namespace haptic::engine
