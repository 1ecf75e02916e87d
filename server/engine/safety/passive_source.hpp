#pragma once
// A network passivity layer at a device port, and a force from a source that books no energy (a
// ROS 2 node's wrench) through one: what the federation's stages at a port share.

#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/core/vec3.hpp"
#include "engine/safety/network_passivity.hpp"

namespace haptic::engine {

/// A network passivity layer's parameters at a device port: its damper capped at what stops the
/// device's `mass` (or, for a torque, its inertia) within one period T; the layer's default cap
/// where that is unknown (0). Units: kg (kg·m²), s.
inline NetworkPassivityParams port_layer_params(double mass, double T) {
  NetworkPassivityParams params;
  params.period = T;
  params.max_deficit_J = kCouplingMaxDeficitJ;
  if (mass > 0.0) params.max_damping = mass / T;
  return params;
}

/// A force F (or a torque) from a source that books no energy, on a body of `mass` (or inertia)
/// at p moving at v (or its summed rotation and angular velocity), through `layer`, whose
/// reservoir R then holds only what the user did against it.
///
/// A held force pushes the mass through ½ (F/m) T² over the period whatever its velocity, which
/// the layer's T F·v does not predict: against a hand holding still, each such period gives the
/// hand up to F²T²/2m the layer cannot take back, and they add up (with the layer alone a held
/// hand let a 3 N push creep the tool out 1.5 cm and got 23 mJ it never put in; 1 cm and 11 mJ
/// with cancel_along_velocity). So F is first scaled (s in [0, 1]) to what R pays for over the
/// coming period, its own push included:
///   s T F·v + s² T² |F|² / 2m ≤ R,
/// with m the device's apparent mass (the hand's adds to it: the real push is smaller, so this
/// errs towards less force). The layer then books what was done and damps any remainder. Nothing
/// is received from the source and all R holds is kept (an unbounded keep): nothing is sent.
inline Vec3 from_passive_source(NetworkPassivity& layer, const Vec3& F_requested, const Vec3& v, const Vec3& p,
                                double mass, double T) {
  Vec3 F = F_requested;
  const double F2 = dot(F, F);
  if (F2 > 0.0) {
    const double a = T * T * F2 / (2.0 * mass);
    const double b = T * dot(F, v);
    const double discriminant = b * b + 4.0 * a * layer.reservoir();
    const double s = discriminant < 0.0 ? 0.0 : std::clamp((-b + std::sqrt(discriminant)) / (2.0 * a), 0.0, 1.0);
    F = s * F;
  }
  return layer.apply(F, v, p, std::numeric_limits<double>::infinity()).F_T_W;
}

}  // namespace haptic::engine
