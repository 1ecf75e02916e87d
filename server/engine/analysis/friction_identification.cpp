#include "engine/analysis/friction_identification.hpp"

#include <array>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>

namespace haptic::engine {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

StepPeak simulate_step_peak(const SingleJointParams& joint, double reference,
                            const StepExperimentSettings& settings) {
  assert(joint.validate().empty());
  assert(settings.gain > 0.0 && settings.max_duration > 0.0);
  const bool sampled = settings.control_period > 0.0;
  const double h = sampled ? settings.control_period : settings.sample_period;
  assert(h > 0.0);
  const double K = settings.gain;

  SingleJointPlant plant(joint, {}, settings.integration);
  // The last four samples y[k−3..k], newest last.
  std::array<double, 4> y{0.0, 0.0, 0.0, 0.0};
  const auto max_steps = static_cast<std::int64_t>(std::ceil(settings.max_duration / h));
  bool moved = false;
  double q_dot_previous = 0.0;  // at sample k−1
  double q_dot_earlier = 0.0;   // at sample k−2
  for (std::int64_t k = 1; k <= max_steps; ++k) {
    if (sampled) {
      plant.step(K * (reference - plant.state().q), h);  // u held over the period
    } else {
      plant.step(0.0, h, [&](double q, double) { return K * (reference - q); });
    }
    y = {y[1], y[2], y[3], plant.state().q};
    const double q_dot = plant.state().q_dot;
    if (!moved || q_dot >= joint.stick_velocity || k < 3) {
      moved = moved || q_dot >= joint.stick_velocity;
      q_dot_earlier = q_dot_previous;
      q_dot_previous = q_dot;
      continue;
    }
    // t_p: where the rate, extrapolated linearly from samples k−2 and k−1 (both still moving),
    // reaches zero. A joint that sticks at its first peak (r < 3 f/K: then K(y_p − r) ≤ f) creeps
    // at the edge of the stick band instead of turning, so neither the samples of y (a plateau)
    // nor the rate at sample k place the turning point; the approach does.
    const double crossing = q_dot_previous / (q_dot_earlier - q_dot_previous);  // samples after k−1
    // The rate has come back to rest or turned: the first maximum is y[k−1] or y[k]. Take one
    // more sample so that whichever it is has a neighbour on each side.
    if (sampled) {
      plant.step(K * (reference - plant.state().q), h);
    } else {
      plant.step(0.0, h, [&](double q, double) { return K * (reference - q); });
    }
    y = {y[1], y[2], y[3], plant.state().q};
    // Now y[3] is sample k+1; candidates are y[1] (k−1) and y[2] (k).
    const std::size_t m = y[2] >= y[1] ? 2 : 1;
    const double a = y[m - 1];
    const double b = y[m];
    const double c = y[m + 1];
    const double curvature = a - 2.0 * b + c;
    double peak = b;  // y_p: the vertex of the parabola through the three samples
    if (curvature < 0.0) peak = b - 0.125 * (a - c) * (a - c) / curvature;
    return {reference, peak, (static_cast<double>(k - 1) + crossing) * h};
  }
  return {reference, kNaN, kNaN};
}

FrictionIdentification identify_from_line(double slope, double r_intercept, double peak_time,
                                          double gain) {
  FrictionIdentification id;
  id.slope = slope;
  id.r_intercept = r_intercept;
  id.peak_time = peak_time;
  id.coulomb = gain * r_intercept;                                  // eq. 5.6
  const double beta = -std::log(slope - 1.0);                       // L2613
  id.damping_ratio = beta / std::sqrt(kPi * kPi + beta * beta);     // eq. 5.8
  id.natural_frequency =
      kPi / (peak_time * std::sqrt(1.0 - id.damping_ratio * id.damping_ratio));  // eq. 5.9
  id.inertia = gain / (id.natural_frequency * id.natural_frequency);             // L2645
  id.damping = 2.0 * id.damping_ratio * std::sqrt(gain * id.inertia);            // L2649
  return id;
}

FrictionIdentification identify_from_peaks(std::span<const StepPeak> peaks, double gain) {
  assert(peaks.size() >= 2);
  const double n = static_cast<double>(peaks.size());
  double sr = 0.0, sy = 0.0, st = 0.0;
  for (const StepPeak& p : peaks) {
    sr += p.reference;
    sy += p.peak;
    st += p.peak_time;
  }
  const double mean_r = sr / n;
  const double mean_y = sy / n;
  double srr = 0.0, sry = 0.0;
  for (const StepPeak& p : peaks) {
    srr += (p.reference - mean_r) * (p.reference - mean_r);
    sry += (p.reference - mean_r) * (p.peak - mean_y);
  }
  assert(srr > 0.0);
  const double slope = sry / srr;
  const double intercept = mean_y - slope * mean_r;  // y at r = 0
  return identify_from_line(slope, -intercept / slope, st / n, gain);
}

FrictionIdentification predicted_identification(double inertia, double damping, double coulomb,
                                                double gain) {
  FrictionIdentification id;
  id.inertia = inertia;
  id.damping = damping;
  id.coulomb = coulomb;
  id.natural_frequency = std::sqrt(gain / inertia);                   // eq. 5.7
  id.damping_ratio = damping / (2.0 * std::sqrt(gain * inertia));     // eq. 5.7
  const double root = std::sqrt(1.0 - id.damping_ratio * id.damping_ratio);
  id.slope = 1.0 + std::exp(-id.damping_ratio * kPi / root);          // L2611
  id.peak_time = kPi / (id.natural_frequency * root);                 // L2601
  id.r_intercept = coulomb / gain;                                    // eq. 5.6
  return id;
}

FrictionIdentification identify_joint(const SingleJointParams& joint,
                                      std::span<const double> references,
                                      const StepExperimentSettings& settings,
                                      std::span<StepPeak> peaks) {
  assert(references.size() == peaks.size());
  for (std::size_t i = 0; i < references.size(); ++i) {
    peaks[i] = simulate_step_peak(joint, references[i], settings);
  }
  return identify_from_peaks(peaks, settings.gain);
}

}  // namespace haptic::engine
