#pragma once
// A simulated human operator holding the tool (what a test or a demo puts in the loop instead of a
// person).
//   FOLLOW_TARGET: a hand impedance pulling the tool along a target trajectory,
//                  F = K_h (x_target(t) − p) + B_h (v_target(t) − v); the hand's mass m_h moves
//                  with the tool (a firm grasp), so it adds to the device's inertia.
//   APPLY_FORCE:   a force profile F(t) (constant, step, ramp or sine).
//   NONE:          the hand lets go.
// t is the time since this input was set, so a profile or trajectory starts when it is sent.
// Everything here is trivially copyable: it crosses to the loop through a lock-free mailbox.

#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "engine/core/vec3.hpp"

namespace haptic::engine {

/// Where the hand's target is at time t (s since the input was set).
struct TargetTrajectory {
  enum class Shape { kFixed, kLine, kSine };
  Shape shape = Shape::kFixed;
  Vec3 end;                   // kLine: the target moves from HandInput::target to here. Unit: m.
  double duration_s = 0.0;    // kLine: over this time, then holds. Unit: s.
  Vec3 amplitude;             // kSine: target + amplitude sin(2π f t). Unit: m.
  double frequency_hz = 0.0;  // kSine. Unit: Hz.
};

/// A recorded force, sampled at a fixed period and played back with linear interpolation between
/// samples. After the last sample it holds that sample's value (record a zero to let go), unless
/// `repeat`, in which case it wraps round to the first sample. Kept inline (no heap) so that the
/// input stays trivially copyable; longer recordings are resampled by the client.
struct RecordedForce {
  static constexpr std::uint32_t kMaxSamples = 512;
  std::uint32_t count = 0;
  double sample_period_s = 0.0;  // Unit: s; > 0 when count > 0.
  bool repeat = false;
  std::array<Vec3, kMaxSamples> samples{};  // Unit: N, in W.
};

/// A force over time; `HandInput::force` is its amplitude (not used by kRecorded).
struct ForceProfile {
  enum class Shape { kConstant, kStep, kRamp, kSine, kRecorded };
  Shape shape = Shape::kConstant;
  double start_s = 0.0;       // kStep, kRamp: when it begins. Unit: s.
  double rise_s = 0.0;        // kRamp: from 0 to the amplitude over this time. Unit: s.
  double frequency_hz = 0.0;  // kSine: offset + amplitude sin(2π f t). Unit: Hz.
  Vec3 offset;                // kSine. Unit: N.
  RecordedForce recorded;     // kRecorded.
};

struct HandInput {
  enum class Mode { kNone, kFollowTarget, kApplyForce };
  Mode mode = Mode::kNone;
  Vec3 target;              // Unit: m, in W. The trajectory's start (or the fixed target).
  double stiffness = 0.0;   // Unit: N/m.
  double damping = 0.0;     // Unit: N*s/m.
  double mass = 0.0;        // Hand mass moving with the tool. Unit: kg.
  TargetTrajectory trajectory;
  Vec3 force;               // Unit: N, in W. The profile's amplitude.
  ForceProfile profile;
};

/// Grip presets at the two ends of the range a hand spans (mass 0.2–2 kg, stiffness 2–800 N/m,
/// damping 3–15 N·s/m): a loose grip is light and soft, a tight one heavy and stiff.
struct Grip {
  double mass;       // Unit: kg.
  double stiffness;  // Unit: N/m.
  double damping;    // Unit: N*s/m.
};
inline constexpr Grip kLooseGrip{0.2, 2.0, 3.0};
inline constexpr Grip kTightGrip{2.0, 800.0, 15.0};

/// Target position and velocity at time t. Units: m, m/s.
inline void target_at(const HandInput& hand, double t, Vec3& position, Vec3& velocity) {
  const TargetTrajectory& path = hand.trajectory;
  switch (path.shape) {
    case TargetTrajectory::Shape::kLine:
      if (path.duration_s > 0.0 && t < path.duration_s) {
        const Vec3 rate = (1.0 / path.duration_s) * (path.end - hand.target);
        position = hand.target + t * rate;
        velocity = rate;
      } else {
        position = path.end;
        velocity = {};
      }
      return;
    case TargetTrajectory::Shape::kSine: {
      const double w = 2.0 * std::numbers::pi * path.frequency_hz;
      position = hand.target + std::sin(w * t) * path.amplitude;
      velocity = (w * std::cos(w * t)) * path.amplitude;
      return;
    }
    case TargetTrajectory::Shape::kFixed:
      break;
  }
  position = hand.target;
  velocity = {};
}

/// A recording's force at time t ≥ 0. Unit: N.
inline Vec3 recorded_force(const RecordedForce& recording, double t) {
  if (recording.count == 0) return {};
  const double position = t / recording.sample_period_s;  // in samples
  const auto n = static_cast<double>(recording.count);
  if (!recording.repeat && position >= n - 1.0) return recording.samples[recording.count - 1];
  const double wrapped = recording.repeat ? std::fmod(position, n) : position;
  const auto i = static_cast<std::uint32_t>(wrapped);
  const std::uint32_t next = i + 1 < recording.count ? i + 1 : 0;
  const double f = wrapped - static_cast<double>(i);
  return (1.0 - f) * recording.samples[i] + f * recording.samples[next];
}

/// The force profile at time t. Unit: N.
inline Vec3 profile_force(const HandInput& hand, double t) {
  const ForceProfile& profile = hand.profile;
  switch (profile.shape) {
    case ForceProfile::Shape::kRecorded:
      return recorded_force(profile.recorded, t);
    case ForceProfile::Shape::kStep:
      return t >= profile.start_s ? hand.force : Vec3{};
    case ForceProfile::Shape::kRamp: {
      if (t < profile.start_s) return {};
      if (profile.rise_s <= 0.0 || t >= profile.start_s + profile.rise_s) return hand.force;
      return ((t - profile.start_s) / profile.rise_s) * hand.force;
    }
    case ForceProfile::Shape::kSine:
      return profile.offset + std::sin(2.0 * std::numbers::pi * profile.frequency_hz * t) * hand.force;
    case ForceProfile::Shape::kConstant:
      break;
  }
  return hand.force;
}

/// Force of the hand on the tool at tool position p_WT and velocity v_WT, t seconds after the
/// input was set. Unit: N. (The hand's mass is not a force: the device adds it to its inertia.)
inline Vec3 hand_force(const HandInput& hand, const Vec3& p_WT, const Vec3& v_WT, double t = 0.0) {
  switch (hand.mode) {
    case HandInput::Mode::kFollowTarget: {
      Vec3 x_target, v_target;
      target_at(hand, t, x_target, v_target);
      return hand.stiffness * (x_target - p_WT) + hand.damping * (v_target - v_WT);
    }
    case HandInput::Mode::kApplyForce:
      return profile_force(hand, t);
    case HandInput::Mode::kNone:
      break;
  }
  return {};
}

/// The mass the hand adds to the tool: only while it holds it (FOLLOW_TARGET). Unit: kg.
constexpr double hand_mass(const HandInput& hand) {
  return hand.mode == HandInput::Mode::kFollowTarget ? hand.mass : 0.0;
}

}  // namespace haptic::engine
