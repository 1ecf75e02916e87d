#include "engine/analysis/moving_stretch_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>

namespace haptic::engine::identification {
namespace {

/// A stretch shorter than this (after its first and last samples are left out) is not fitted:
/// x₀ and v₀ take two of its samples.
constexpr std::size_t kMinimumStretch = 6;
/// Fewer samples in stretches than this and the fit is refused.
constexpr std::size_t kMinimumSamples = 64;

/// `values` (one stretch, at t = j T) less their least-squares line a + b t.
void project_out_line(std::span<double> values) {
  const auto n = static_cast<double>(values.size());
  const double mean_j = (n - 1.0) / 2.0;
  double mean_v = 0.0;
  for (const double v : values) mean_v += v;
  mean_v /= n;
  double sjj = 0.0, sjv = 0.0;
  for (std::size_t j = 0; j < values.size(); ++j) {
    const double dj = static_cast<double>(j) - mean_j;
    sjj += dj * dj;
    sjv += dj * (values[j] - mean_v);
  }
  const double slope = sjj > 0.0 ? sjv / sjj : 0.0;
  for (std::size_t j = 0; j < values.size(); ++j) values[j] -= mean_v + slope * (static_cast<double>(j) - mean_j);
}

}  // namespace

MovingStretchFit::MovingStretchFit(std::span<const double> force, std::span<const double> position, double period_s,
                                   std::size_t begin, std::size_t samples_per_period, std::size_t periods,
                                   double noise_rms_m, std::optional<double> quantization_m)
    : force_(force.begin(), force.end()), period_(period_s), fitted_ticks_(samples_per_period * periods) {
  const std::size_t size = std::min(force.size(), position.size());
  const double t = period_s;
  const std::size_t end = std::min(begin + fitted_ticks_, size);
  // The velocity over ±k ticks, (x[n+k] − x[n−k]) / (2kT), its noise σ/(√2 k T) and one step over
  // the span q/(2kT): the span the smallest of 1, 2, 4, 8 ticks whose still speed (four times
  // that noise, plus the step) is under a fifth of the rms speed, so that a heavy, slow axis
  // (003's five-bar) is told moving from its noise as a light, fast one (004's gimbal) is.
  const auto velocity_over = [&](std::size_t k) {
    std::vector<double> velocity(size, 0.0);
    double squares = 0.0;
    std::size_t count = 0;
    for (std::size_t n = std::max(begin, k); n < end && n + k < size; ++n) {
      velocity[n] = (position[n + k] - position[n - k]) / (2.0 * static_cast<double>(k) * t);
      squares += velocity[n] * velocity[n];
      ++count;
    }
    return std::pair{velocity, count > 0 ? std::sqrt(squares / static_cast<double>(count)) : 0.0};
  };
  std::size_t span = 1;
  std::vector<double> velocity;
  for (span = 1;; span *= 2) {
    double rms_speed = 0.0;
    std::tie(velocity, rms_speed) = velocity_over(span);
    const double k = static_cast<double>(span);
    const double noise_speed =
        4.0 * noise_rms_m / (std::sqrt(2.0) * k * t) + quantization_m.value_or(0.0) / (2.0 * k * t);
    still_below_ = std::max(noise_speed, 0.02 * rms_speed);
    if (noise_speed < 0.2 * rms_speed || span >= 8) break;
  }
  // Runs of samples moving one way faster than that; each less the span at either end, where the
  // axis may have been still for part of the ticks the difference spans.
  std::size_t n = std::max(begin, span);
  while (n < end) {
    const double direction = velocity[n] > 0.0 ? 1.0 : -1.0;
    if (!(velocity[n] * direction > still_below_)) {
      ++n;
      continue;
    }
    std::size_t last = n;
    while (last + 1 < end && velocity[last + 1] * direction > still_below_) ++last;
    if (last >= n + kMinimumStretch + 2 * span - 1) {
      Stretch stretch{n + span, last + 1 - n - 2 * span, (n + span - begin) / samples_per_period};
      std::vector<std::array<double, kFixedColumns>> columns(stretch.length);
      std::vector<double> column(stretch.length);
      const double x0 = position[stretch.first_tick];
      double integral = 0.0;  // ∫(x − x₀) by the trapezoidal rule. Unit: m·s.
      for (std::size_t j = 0; j < stretch.length; ++j) {
        const std::size_t tick = stretch.first_tick + j;
        if (j > 0) integral += 0.5 * t * (position[tick - 1] + position[tick] - 2.0 * x0);
        const double time = static_cast<double>(j) * t;
        columns[j] = {position[tick], direction * time * time / 2.0, time * time / 2.0, integral};
      }
      for (std::size_t c = 0; c < kFixedColumns; ++c) {
        for (std::size_t j = 0; j < stretch.length; ++j) column[j] = columns[j][c];
        project_out_line(column);
        for (std::size_t j = 0; j < stretch.length; ++j) columns[j][c] = column[j];
      }
      stretches_.push_back(stretch);
      fixed_.insert(fixed_.end(), columns.begin(), columns.end());
    }
    n = last + 1;
  }
}

std::size_t MovingStretchFit::moving_samples() const { return fixed_.size(); }

double MovingStretchFit::moving_fraction() const {
  return fitted_ticks_ > 0 ? static_cast<double>(fixed_.size()) / static_cast<double>(fitted_ticks_) : 0.0;
}

std::vector<double> MovingStretchFit::double_integral(double lag) const {
  // Over tick n the lagged force is f + (g − f) e^{−s/τ_a}, g its value at the tick's start: its
  // integral V and double integral P advance exactly. P and V are kept side by side (2n, 2n + 1)
  // for the cubic Hermite interpolation of a fractional delay.
  const double t = period_;
  const double decay = lag > 0.0 ? std::exp(-t / lag) : 0.0;
  const double once = lag > 0.0 ? lag * (1.0 - decay) : 0.0;          // ∫₀ᵀ e^{−s/τ} ds
  const double twice = lag > 0.0 ? lag * (t - lag * (1.0 - decay)) : 0.0;  // ∫₀ᵀ∫₀ˢ e^{−u/τ} du ds
  std::vector<double> out(2 * (force_.size() + 1), 0.0);
  double lagged = 0.0, integral = 0.0, double_integral = 0.0;
  for (std::size_t n = 0; n < force_.size(); ++n) {
    const double f = force_[n];
    const double transient = lag > 0.0 ? lagged - f : 0.0;
    double_integral += integral * t + f * t * t / 2.0 + transient * twice;
    integral += f * t + transient * once;
    lagged = f + transient * decay;
    out[2 * (n + 1)] = double_integral;
    out[2 * (n + 1) + 1] = integral;
  }
  return out;
}

Parameters MovingStretchFit::solve(std::span<const double> force_integral, double delay, double lag,
                                   std::optional<std::size_t> left_out) const {
  const double t = period_;
  // ∬F_a at t_n − (τ − T/2): the hold's half tick is in ∬F_a already.
  const double shift = (delay - 0.5 * t) / t;
  const std::size_t nodes = force_integral.size() / 2;
  const auto shifted = [&](std::size_t tick) {
    const double at = static_cast<double>(tick) - shift;
    const double floor_at = std::floor(at);
    if (floor_at < 0.0 || floor_at + 1.0 >= static_cast<double>(nodes)) return 0.0;
    const auto j = static_cast<std::size_t>(floor_at);
    const double s = at - floor_at;
    const double p0 = force_integral[2 * j], v0 = force_integral[2 * j + 1];
    const double p1 = force_integral[2 * j + 2], v1 = force_integral[2 * j + 3];
    const double s2 = s * s, s3 = s2 * s;
    return (2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * t * v0 + (-2 * s3 + 3 * s2) * p1 + (s3 - s2) * t * v1;
  };
  double ata[4][4] = {}, atb[4] = {};
  double target_power = 0.0;
  std::vector<double> force_column;
  std::size_t offset = 0;
  const auto each_sample = [&](auto&& use) {
    offset = 0;
    for (const Stretch& stretch : stretches_) {
      const std::size_t first = offset;
      offset += stretch.length;
      if (left_out && stretch.period == *left_out) continue;
      force_column.resize(stretch.length);
      for (std::size_t j = 0; j < stretch.length; ++j) force_column[j] = shifted(stretch.first_tick + j);
      project_out_line(force_column);
      for (std::size_t j = 0; j < stretch.length; ++j) {
        const auto& fixed = fixed_[first + j];
        use(std::array<double, 4>{force_column[j], -fixed[1], -fixed[2], -fixed[3]}, fixed[0]);
      }
    }
  };
  each_sample([&](const std::array<double, 4>& row, double y) {
    for (std::size_t r = 0; r < 4; ++r) {
      atb[r] += row[r] * y;
      for (std::size_t c = 0; c < 4; ++c) ata[r][c] += row[r] * row[c];
    }
    target_power += y * y;
  });
  std::array<bool, 4> used{};
  const std::array<double, 4> theta = least_squares(ata, atb, used);  // 1/m, c/m, f0/m, b/m
  Parameters p;
  p.mass = used[0] ? 1.0 / theta[0] : std::numeric_limits<double>::quiet_NaN();
  p.coulomb = theta[1] * p.mass;
  p.offset = theta[2] * p.mass;
  p.damping = used[3] ? theta[3] * p.mass : std::numeric_limits<double>::quiet_NaN();
  p.delay = delay;
  p.lag = lag;
  p.force_power = target_power;
  each_sample([&](const std::array<double, 4>& row, double y) {
    double model = 0.0;
    for (std::size_t r = 0; r < 4; ++r) model += row[r] * theta[r];
    p.residual += (y - model) * (y - model);
  });
  if (!std::isfinite(p.residual) || !std::isfinite(p.mass)) p.residual = std::numeric_limits<double>::infinity();
  return p;
}

std::optional<Parameters> MovingStretchFit::fit(std::optional<std::size_t> left_out, double max_delay, double max_lag,
                                                std::string& why, const Parameters* near) const {
  std::size_t count = 0;
  for (const Stretch& stretch : stretches_) count += !(left_out && stretch.period == *left_out) ? stretch.length : 0;
  if (count < kMinimumSamples) {
    why = "the axis moved one way faster than " + std::to_string(still_below_) + " m/s for " + std::to_string(count) +
          " samples in stretches of at least " + std::to_string(kMinimumStretch) + " ticks (at least " +
          std::to_string(kMinimumSamples) + " are needed): friction held it; raise the amplitude or the band";
    return std::nullopt;
  }
  // The whole range on a grid, then a golden section about the best point; near a given fit, only
  // one step of the whole range's grids either side of it.
  constexpr std::size_t kLagGrid = 12, kDelayGrid = 24, kFinalDelayGrid = 80;
  const auto range = [&](double value, double limit, std::size_t grid) {
    if (!near) return std::pair{0.0, limit};
    const double step = limit / static_cast<double>(grid);
    return std::pair{std::max(0.0, value - step), std::min(limit, value + step)};
  };
  const auto best_delay = [&](double lag, std::size_t grid, int refine) {
    const std::vector<double> integral = double_integral(lag);
    const auto [lo, hi] = range(near ? near->delay : 0.0, max_delay, kDelayGrid);
    return minimise([&](double tau) { return solve(integral, tau, lag, left_out); }, lo, hi, near ? 2 : grid, refine);
  };
  double lag = 0.0;
  if (max_lag > 0.0) {
    const auto [lo, hi] = range(near ? near->lag : 0.0, max_lag, kLagGrid);
    lag = minimise([&](double l) { return best_delay(l, kDelayGrid, 20); }, lo, hi, near ? 2 : kLagGrid, 16).lag;
  }
  Parameters result = best_delay(lag, kFinalDelayGrid, 40);
  if (!std::isfinite(result.mass) || !std::isfinite(result.damping)) {
    why = "the fit is singular (the moving stretches do not tell mass from damping)";
    return std::nullopt;
  }
  return result;
}

}  // namespace haptic::engine::identification
