#pragma once
// The excitation of a device port's identification (docs/identification.md), a stage of the tick:
// a multisine force (engine/analysis/system_identification) along one axis of W, from the run's
// first tick, added to the scene's force before the force guard, so that it reaches the device as
// every command does (the guard's magnitude and rate limits, Jᵀ, the actuators). It stops for good,
// its force zero from then on, when the tool leaves its box or moves faster than allowed; what
// stopped it, and when, is kept for the run's report.

#include <cstdint>

#include "engine/analysis/system_identification.hpp"
#include "engine/core/vec3.hpp"
#include "runtime/device.hpp"

namespace haptic::runtime {

struct ExcitationLimits {
  /// How far from where it was at the first tick the tool may go along each axis of W. Unit: m. > 0.
  double box_half_width_m = 0.05;
  double max_speed_m_s = 0.5;  // |v_WT| beyond which it stops. Unit: m/s. > 0.
};

/// A spring and a damper about the start, along the axis, added to the multisine: they keep a
/// device that friction lets wander (stick and slip walks it off) near where its mass is
/// measured. They are part of the command, and the fit takes the command as it was written,
/// whatever it is made of. Keep K below what the device's lag makes unstable (with a lag τ_a and
/// no damping of its own, B > τ_a K), and the multisine's peak plus their force within its limit.
struct ExcitationCentering {
  double stiffness = 0.0;  // K. Unit: N/m. >= 0; 0: none.
  double damping = 0.0;    // B. Unit: N·s/m. >= 0.
};

class ExcitationStage {
 public:
  enum class Stop { kNone, kLeftTheBox, kTooFast };

  /// axis_W: the direction of the force, a unit vector in W.
  ExcitationStage(engine::Multisine signal, engine::Vec3 axis_W, ExcitationLimits limits,
                  ExcitationCentering centering = {});

  /// On the loop, once a tick with a good reading: the force for run tick `tick` (1, 2, ...; the
  /// multisine's tick is tick − 1), with the centering's. Zero once stopped; past the signal's end,
  /// the centering's alone. Unit: N, in W.
  engine::Vec3 force(const ToolReading& reading, std::uint64_t tick);

  Stop stop() const { return stop_; }
  std::uint64_t stop_tick() const { return stop_tick_; }
  /// The tool's position and speed when it stopped. Unit: m, m/s.
  engine::Vec3 stop_position() const { return stop_position_; }
  double stop_speed() const { return stop_speed_; }
  /// The tool's position at the first tick (the box's centre). Unit: m.
  engine::Vec3 start_position() const { return start_; }
  const engine::Multisine& signal() const { return signal_; }
  const engine::Vec3& axis() const { return axis_; }

 private:
  engine::Multisine signal_;
  engine::Vec3 axis_;
  ExcitationLimits limits_;
  ExcitationCentering centering_;
  Stop stop_ = Stop::kNone;
  std::uint64_t stop_tick_ = 0;
  engine::Vec3 stop_position_{};
  double stop_speed_ = 0.0;
  engine::Vec3 start_{};  // the first tick's position, the box's centre
  bool started_ = false;
};

}  // namespace haptic::runtime
