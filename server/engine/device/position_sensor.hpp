#pragma once
// A simulated position sensor (docs/identification.md): what a real device's measurement adds to
// the truth — Gaussian noise, then quantization to a step, per axis — and the velocity a device
// counting an encoder reports, the backward difference of its measured positions. Seeded, so a
// lockstep run is the same run every time. No allocation per reading.

#include <cmath>
#include <cstdint>
#include <random>

#include "engine/core/vec3.hpp"

namespace haptic::engine {

struct PositionSensorParams {
  double noise_m = 0.0;         // rms, per axis. Unit: m. >= 0.
  double quantization_m = 0.0;  // the step. Unit: m. >= 0; 0: none.
  std::uint64_t seed = 0;
};

class PositionSensor {
 public:
  explicit PositionSensor(const PositionSensorParams& params)
      : params_(params), random_(params.seed), noise_(0.0, 1.0) {}

  /// The measured position for the true `p` (m, W).
  Vec3 measure(const Vec3& p) { return {axis(p.x), axis(p.y), axis(p.z)}; }

  /// The measured position and the velocity a device would report with it: (measured − last
  /// measured) / period_s; 0 for the first reading or a period not > 0. Unit: m, m/s.
  void read(const Vec3& p, double period_s, Vec3& measured, Vec3& velocity) {
    measured = measure(p);
    velocity = have_last_ && period_s > 0.0 ? (measured - last_) * (1.0 / period_s) : Vec3{};
    last_ = measured;
    have_last_ = true;
  }

 private:
  double axis(double x) {
    if (params_.noise_m > 0.0) x += params_.noise_m * noise_(random_);
    if (params_.quantization_m > 0.0) x = params_.quantization_m * std::round(x / params_.quantization_m);
    return x;
  }

  PositionSensorParams params_;
  std::mt19937_64 random_;
  std::normal_distribution<double> noise_;
  Vec3 last_{};
  bool have_last_ = false;
};

}  // namespace haptic::engine
