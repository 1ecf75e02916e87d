#pragma once
// A simulated position sensor (docs/identification.md): what a real device's measurement adds to
// the truth — Gaussian noise, then quantization to a step, per axis — and the velocity a device
// counting an encoder reports, the backward difference of its measured positions. Seeded, so a
// lockstep run is the same run every time. No allocation per reading.

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>

#include "engine/core/vec3.hpp"

namespace haptic::engine {

/// One reading of one axis: `x` plus `noise_rms` of Gaussian noise, then rounded to a whole
/// number of `step`s (no rounding when `step` is 0). Units: the axis's (m or rad).
inline double sense_axis(double x, double noise_rms, double step, std::mt19937_64& random,
                         std::normal_distribution<double>& unit_normal) {
  if (noise_rms > 0.0) x += noise_rms * unit_normal(random);
  if (step > 0.0) x = step * std::round(x / step);
  return x;
}

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
  double axis(double x) { return sense_axis(x, params_.noise_m, params_.quantization_m, random_, noise_); }

  PositionSensorParams params_;
  std::mt19937_64 random_;
  std::normal_distribution<double> noise_;
  Vec3 last_{};
  bool have_last_ = false;
};

/// The same sensor on a device's joints (docs/identification.md): per joint, noise and a step in
/// the joint's own unit (rad for a revolute joint, m for a prismatic one), for a device that
/// reports joint angles rather than a position in W. N is the largest joint count.
template <std::size_t N>
struct JointEncoderParams {
  std::array<double, N> noise{};         // rms per joint. Unit: the joint's. >= 0.
  std::array<double, N> quantization{};  // the step per joint; 0: none. Unit: the joint's.
  std::uint64_t seed = 0;
};

template <std::size_t N>
class JointEncoder {
 public:
  explicit JointEncoder(const JointEncoderParams<N>& params)
      : params_(params), random_(params.seed), noise_(0.0, 1.0) {}

  /// The first `joints` of `q` as measured, and their rates as a device counting the encoder
  /// reports them: (measured − last measured) / period_s, 0 for the first reading or a period not
  /// > 0. Joints from `joints` on are left as they are.
  void read(std::array<double, N>& q, std::array<double, N>& q_dot, std::size_t joints, double period_s) {
    for (std::size_t i = 0; i < joints && i < N; ++i) {
      q[i] = sense_axis(q[i], params_.noise[i], params_.quantization[i], random_, noise_);
      q_dot[i] = have_last_ && period_s > 0.0 ? (q[i] - last_[i]) / period_s : 0.0;
      last_[i] = q[i];
    }
    have_last_ = true;
  }

 private:
  JointEncoderParams<N> params_;
  std::mt19937_64 random_;
  std::normal_distribution<double> noise_;
  std::array<double, N> last_{};
  bool have_last_ = false;
};

}  // namespace haptic::engine
