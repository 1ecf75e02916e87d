#pragma once
// Whether a run rings up: a stability verdict by growth, not by size. A verdict that waits for a
// run to pass some multiple of its reference's largest value, or to create some energy in a fixed
// time, cannot see a slow ring-up (a closed-loop pole at 1.0014 grows the energy 2.5–3× in 2 s
// and passes neither). The growth rate of the run's envelope is measured instead: the largest
// |size| in each window of the span fitted, its logarithm fitted by least squares against the
// windows' middles. A pole p per sample of period T gives a rate ln|p| / T (1/s): a pole at 1.001
// at 1 kHz is 1.0/s.
//
// Off the loop (studies, tests).

#include <cstddef>
#include <span>

namespace haptic::engine {

struct GrowthFit {
  /// The envelope's growth rate. Unit: 1/s. −infinity where fewer than three windows' envelopes
  /// stand above the floor (the run decayed into rounding): it does not grow.
  double rate_per_s;
  std::size_t windows = 0;   // windows fitted (those above the floor)
  double last_envelope = 0;  // the last window's largest |size|
};

/// The envelope of `size` (one value per `sample_period_s`, any sign: its magnitude counts) over
/// [from_s, end) in windows of `window_s` (a partial last window is left out), fitted as above;
/// windows whose envelope is at or below `floor` are left out of the fit.
GrowthFit envelope_growth(std::span<const double> size, double sample_period_s, double from_s, double window_s,
                          double floor);

/// The growth rate from which a run counts as ringing up: a pole at 1.0001 per millisecond
/// (≈ 0.1/s, 1.1× in a second). Stable runs decay (or, undamped, hold) and fit well below it;
/// margin enough for the envelope's sampling. Unit: 1/s.
inline constexpr double kRingUpRate = 0.1;

/// Whether `run` rings up beside `reference` (the same measure of a run known to be stable, or
/// none): its rate exceeds the reference's, or 0 where the reference decays, by kRingUpRate.
bool rings_up(const GrowthFit& run, const GrowthFit* reference = nullptr);

}  // namespace haptic::engine
