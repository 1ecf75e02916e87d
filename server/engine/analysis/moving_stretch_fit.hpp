#pragma once
// A device axis fitted in time over the stretches where it moves (docs/identification.md,
// "Stick and slip"): system_identification.hpp's
//
//   F(t − τ) / (1 + sτ_a) = m ẍ + b ẋ + c sgn(ẋ) + f0                                   (1)
//
// holds only while the axis moves. Where Coulomb friction holds it still through part of each
// period (004's joystick: a light gimbal, a motor behind an 8.8 ms lag and 1.2 N of friction at
// the handle), the stuck stretches are no mass-damper, and a fit at the harmonics sees them as
// distortion. Here (1) is fitted over each stretch where the axis moved one way, where sgn(ẋ) is
// known, integrated twice from the stretch's start (the integral method of continuous-time
// identification; Garnier & Young, "Identification of Continuous-time Models from Sampled
// Data", 2008, ch. 1):
//
//   x(t) = x₀ + v₀ t + (1/m) ∬F_a(t − τ) − ((c sgn ẋ + f0)/m) t²/2 − (b/m) ∫(x − x₀)      (2)
//
// linear in (1/m, c/m, f0/m, b/m) once each stretch's x₀ + v₀ t is projected out of every column.
// The positions are the target, so an encoder's steps and the noise enter as the target's error
// (unbiased), not as a regressor's, as they would in a difference quotient for ẍ (an encoder of
// 92 µm at 004's handle made a second difference 40 to 60 % off); the one measured regressor,
// ∫x, averages them. ∬F_a is exact under the loop's hold with the lag's response between ticks;
// it carries the hold's half tick, so τ counts it as (1) does. τ and τ_a are searched as the
// harmonic fit searches them.
//
// Internal to engine/analysis (used by identify_axis). Off the loop.

#include <array>
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "engine/analysis/identification_fit.hpp"

namespace haptic::engine::identification {

class MovingStretchFit {
 public:
  /// `force` the command written in each tick and `position` the reading of that tick, from the
  /// run's first tick (the lag's filter starts there, at rest); fitted over the ticks
  /// [begin, begin + periods × samples_per_period). `noise_rms_m` and `quantization_m` set the
  /// speed below which a sample is taken for still: the velocity is the difference over ±k ticks
  /// (k of 1, 2, 4, 8: the smallest whose threshold is under a fifth of the rms speed), the
  /// threshold four times its noise plus one step over the span, and at least 2 % of the rms
  /// speed (slower, the friction's band, not (1), holds). Period T in s.
  MovingStretchFit(std::span<const double> force, std::span<const double> position, double period_s,
                   std::size_t begin, std::size_t samples_per_period, std::size_t periods, double noise_rms_m,
                   std::optional<double> quantization_m);

  /// The fit of (2) over every stretch but those starting in period `left_out` (none: all of
  /// them), τ in [0, max_delay] and τ_a in [0, max_lag] (none where max_lag is 0). Its residual
  /// and force_power are the positions' (m²): the relative residual is of the motion's rms.
  /// `near`: a fit of all the periods, about whose τ and τ_a a jackknife's refit searches (one
  /// grid step of the whole range either side), as its own optimum lies there: each refit then
  /// evaluates a fifth as many (τ, τ_a).
  /// Empty, with `why`, where too few samples moved.
  std::optional<Parameters> fit(std::optional<std::size_t> left_out, double max_delay, double max_lag,
                                std::string& why, const Parameters* near = nullptr) const;

  /// The samples in the stretches, and their share of the fitted ticks.
  std::size_t moving_samples() const;
  double moving_fraction() const;
  /// The speed below which a sample is still. Unit: m/s.
  double still_below() const { return still_below_; }

 private:
  struct Stretch {
    std::size_t first_tick = 0, length = 0;
    std::size_t period = 0;  // of its first tick
  };
  /// Per stretch and sample, (2)'s columns that do not depend on τ and τ_a, each with the
  /// stretch's x₀ + v₀ t projected out: 0 the positions (the target), 1 sgn(ẋ) t²/2, 2 t²/2,
  /// 3 ∫(x − x₀).
  static constexpr std::size_t kFixedColumns = 4;
  /// ∬F_a dt from the run's start at every tick, for a lag τ_a (exact under the hold). Unit: N·s².
  std::vector<double> double_integral(double lag) const;
  Parameters solve(std::span<const double> force_integral, double delay, double lag,
                   std::optional<std::size_t> left_out) const;

  std::vector<double> force_;
  double period_;
  std::size_t fitted_ticks_;
  double still_below_ = 0.0;
  std::vector<Stretch> stretches_;
  std::vector<std::array<double, kFixedColumns>> fixed_;  // the stretches' samples, in order
};

}  // namespace haptic::engine::identification
