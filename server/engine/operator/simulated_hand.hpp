#pragma once
// A simulated human operator holding the tool (what a test or a demo puts in the loop instead of a
// person). FOLLOW_TARGET: a spring-damper hand, F = K_h (target - p) - B_h v. APPLY_FORCE: a
// constant push. NONE: the hand lets go.

#include "engine/core/vec3.hpp"

namespace haptic::engine {

struct HandInput {
  enum class Mode { kNone, kFollowTarget, kApplyForce };
  Mode mode = Mode::kNone;
  Vec3 target;              // Unit: m, in W.
  double stiffness = 0.0;   // Unit: N/m.
  double damping = 0.0;     // Unit: N*s/m.
  Vec3 force;               // Unit: N, in W.
};

/// Force of the hand on the tool at tool position p_WT and velocity v_WT. Unit: N.
constexpr Vec3 hand_force(const HandInput& hand, const Vec3& p_WT, const Vec3& v_WT) {
  switch (hand.mode) {
    case HandInput::Mode::kFollowTarget:
      return hand.stiffness * (hand.target - p_WT) - hand.damping * v_WT;
    case HandInput::Mode::kApplyForce:
      return hand.force;
    case HandInput::Mode::kNone:
      break;
  }
  return {};
}

}  // namespace haptic::engine
