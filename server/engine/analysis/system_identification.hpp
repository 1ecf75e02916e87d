#pragma once
// A device axis identified from a periodic excitation (docs/identification.md): the force applied
// along one axis is a multisine, the measured position is recorded, and the axis is fitted as
//
//   F(t − τ) = m ẍ(t) + b ẋ(t) + c sgn(ẋ(t)) + f0                                      (1)
//
// m the apparent mass (kg), b the viscous damping (N·s/m), c the Coulomb friction (N), f0 a
// constant force (N: a load such as uncompensated gravity; with c it gives the force friction
// resists in each direction, c + f0 moving +, c − f0 moving −), τ the pure delay between the
// command and the measurement (s). Where asked, the force the device applies is the command
// through a first-order lag, F/(1 + sτ_a) (an amplifier's or a motor's time constant, 004's
// 8.8 ms), and τ_a is fitted beside τ.
//
// Why a multisine and averaging (Pintelon & Schoukens, "System Identification: A Frequency Domain
// Approach", 2nd ed. 2012, ch. 2–3): the excitation is periodic, so the response in steady state
// is too; the average of P periods keeps it and divides the noise's power by P, the noise is what
// the periods disagree on (its level measured, not assumed), and the derivatives of the average
// are exact at the excited harmonics (jω X_k, −ω² X_k), where a difference quotient of noisy,
// quantized positions would amplify the noise. (1) is then a linear least-squares problem at the
// excited harmonics for (m, b, c), with sgn(ẋ) taken from the band-limited velocity, and τ found
// by a one-dimensional search of the residual. The constant term comes from the mean force.
// Each estimate's 95 % interval is a delete-one-period jackknife (the fit repeated with each period
// left out): it holds whatever the noise's colour, and it widens honestly with too few periods.
//
// An axis that friction holds still through part of each period breaks (1) there; for it (1) is
// fitted in time instead, over the stretches where it moved (FitMethod::kMovingStretches,
// engine/analysis/moving_stretch_fit), with the same search for τ and τ_a and the same jackknife.
//
// Off the loop: nothing here runs in a tick.

#include <complex>
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace haptic::engine {

/// A periodic multisine force with a ramp in and out (the excitation of one axis).
struct MultisineParams {
  double sample_period_s = 1e-3;      // the loop's period T. Unit: s. > 0.
  std::size_t samples_per_period = 2048;  // N: the multisine's period is N T. >= 16.
  double f_min_hz = 2.0;              // lowest excited frequency (rounded to a harmonic of 1/(N T)). Unit: Hz.
  double f_max_hz = 40.0;             // highest (at most a quarter of the sample rate). Unit: Hz.
  std::size_t max_harmonics = 24;     // excited harmonics, log-spaced between them; >= 3.
  double amplitude_n = 1.0;           // the force's peak in steady state. Unit: N. > 0.
  double ramp_s = 0.5;                // raised-cosine ramp in and out. Unit: s. >= 0.
  std::size_t settle_periods = 1;     // full periods after the ramp left out of the fit (transient)
  std::size_t periods = 8;            // full periods fitted; >= 4 (the jackknife's minimum)
};

/// The designed signal: its harmonics of f0 = 1/(N T) and their phases (Schroeder's, for a low
/// crest factor), scaled so that its largest value over a period is amplitude_n.
struct Multisine {
  MultisineParams params;
  std::vector<std::size_t> harmonics;  // k: frequency k / (N T)
  std::vector<double> phases;          // rad
  double scale = 0.0;                  // N per unit cosine
  /// One period's sum of the harmonics' cosines, sample by sample (made once: a tick looks it up).
  std::vector<double> period;
  /// Duration of the whole run: ramp, settle and fitted periods, ramp. Unit: s.
  double duration_s() const;
  /// Ticks from the start to the first fitted sample, and the number fitted (periods × N).
  std::size_t fit_begin_tick() const;
  std::size_t fit_ticks() const;
  /// The force at tick i (time i T): the multisine times the ramp envelope; 0 after the end.
  double force_at_tick(std::size_t tick) const;
};

/// Designs the multisine; an empty optional and `why` for parameters out of range.
std::optional<Multisine> design_multisine(const MultisineParams& params, std::string& why);

/// How (1) is fitted.
enum class FitMethod {
  /// At the excited harmonics of the averaged period (above): every tick, the friction as
  /// c sgn(ẋ) throughout. The default.
  kHarmonics,
  /// In time, over the samples where the axis moved one way (engine/analysis/moving_stretch_fit):
  /// for an axis that friction holds still through part of each period, where (1) does not hold.
  kMovingStretches,
};

/// One identified parameter: the estimate, its 95 % interval's half-width, and the jackknife's
/// standard error.
struct Estimate {
  double value = 0.0;
  double half_width_95 = 0.0;
  double standard_error = 0.0;
};

/// The measured and modelled frequency response X/F at the excited harmonics, for a Bode chart.
struct FrequencyPoint {
  double frequency_hz = 0.0;
  std::complex<double> measured;  // X_k / F_k. Unit: m/N.
  /// H(ω) e^{−jωτ} / ((1 + jωτ_a)(−m ω² + j b ω)): the linear part of (1) behind the loop's
  /// hold, whose magnitude is H(ω) = sin(ωT/2)/(ωT/2), and the lag where one was fitted. Unit: m/N.
  std::complex<double> model;
};

struct AxisIdentification {
  Estimate mass;            // m. Unit: kg.
  Estimate damping;         // b. Unit: N·s/m.
  Estimate coulomb;         // c. Unit: N.
  Estimate offset;          // f0. Unit: N.
  /// τ, from the command's tick to its effect on the readings: the hold's T/2 (a perfect loop's:
  /// a command acts over the tick after it is written) and whatever the device adds. Unit: s.
  Estimate delay;
  /// τ_a, a first-order lag between the command and the force the device applies (an
  /// amplifier's or a motor's time constant), where the fit was asked to look for one (else 0):
  /// F_applied = F / (1 + s τ_a) in (1). Unit: s.
  Estimate lag;
  double coulomb_positive = 0.0;  // c + f0: the force to move the axis +. Unit: N.
  double coulomb_negative = 0.0;  // c − f0: the force to move it −. Unit: N.
  /// The measurement's noise: the rms of what consecutive periods disagree on, its smooth part
  /// (a transient, a drift) left out by a second difference in time. Unit: m.
  double noise_rms_m = 0.0;
  /// The positions' quantization step where they lie on a lattice (an encoder along the axis, or
  /// a counted joint through a map whose slope changes slowly: lattice_step); none where they do
  /// not (noise, or a map that mixes several joints' counts). Unit: m.
  std::optional<double> quantization_m;
  /// The rms of (1)'s residual over the averaged period, relative to the force's rms.
  double relative_residual = 0.0;
  std::size_t periods = 0;
  FitMethod method = FitMethod::kHarmonics;
  /// The share of the fitted ticks the fit used: 1 at the harmonics; in time, those where the
  /// axis moved (the rest friction held, or too slow to tell).
  double moving_fraction = 1.0;
  std::vector<FrequencyPoint> response;
};

/// Fits (1) to one axis: `force` and `position` one value per tick (force the command written in
/// that tick, position the reading of that tick) from the excitation's first tick, at least
/// fit_begin_tick() + fit_ticks() long. `max_delay_s` bounds τ's search (default 20 ticks);
/// `max_lag_s` > 0 fits a first-order lag τ_a in [0, max_lag_s] beside it (FrequencyPoint's
/// model and the residual then carry 1/(1 + jωτ_a)). `method`: at the harmonics, or in time where
/// the axis moved (the response's measured points are the harmonics' either way).
/// An empty optional and `why` when the data cannot be fitted (too short, not finite, no motion).
std::optional<AxisIdentification> identify_axis(const Multisine& excitation, std::span<const double> force,
                                                std::span<const double> position, std::string& why,
                                                double max_delay_s = -1.0, double max_lag_s = 0.0,
                                                FitMethod method = FitMethod::kHarmonics);

/// The quantization step of `values` if they lie on a lattice q·n + offset (to 1e-6 of q, plus
/// 1e-9 of q for each step from the lowest), the smallest step seen. Failing that, on a lattice
/// whose step changes slowly along the axis, as a nonlinear map of a counted joint reads (003's
/// five-bar along x: 0.6 − 0.3 sin(n π/6000) m): going up the values, each gap whole local steps
/// (at most 20) within a twentieth of a step, the local step the median of the last eight, or
/// under a fiftieth of it (another joint's count moving the reading a little; such clusters
/// narrower than a twentieth), and at least eight steps; the step is then the median of those
/// seen. None otherwise (noise) or with fewer than three distinct values.
std::optional<double> lattice_step(std::span<const double> values);

}  // namespace haptic::engine
