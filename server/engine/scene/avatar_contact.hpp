#pragma once
// Another site's tool as this site's user touches it (docs/federation.md, "Avatars"): a
// frictionless sphere about the remote tool's position that pushes this tool out and never pulls.

#include <algorithm>

#include "engine/core/vec3.hpp"

namespace haptic::engine {

struct AvatarContact {
  Vec3 F_T_W;             // on this tool, in W. Unit: N.
  double stored_J = 0.0;  // the contact's spring energy, ½ K d². Unit: J.
};

/// This tool at p (velocity v) against a sphere of `radius` about the remote tool at p_remote
/// (velocity v_remote): with d = radius − |p − p_remote| the depth and n the unit vector from the
/// remote tool to this one, F = max(0, K d − B (v − v_remote)·n) n, all scaled by `gain` (a fading
/// avatar's); nothing where the tools do not touch, or sit exactly on each other (no n). Units: m,
/// m/s, N/m, N·s/m.
inline AvatarContact avatar_contact(const Vec3& p, const Vec3& v, const Vec3& p_remote, const Vec3& v_remote,
                                    double radius, double stiffness, double damping, double gain) {
  const Vec3 apart = p - p_remote;
  const double distance = norm(apart);
  const double depth = radius - distance;
  if (!(depth > 0.0 && distance > 0.0)) return {};
  const Vec3 n = (1.0 / distance) * apart;
  const double push = stiffness * depth - damping * dot(v - v_remote, n);
  return {gain * std::max(0.0, push) * n, gain * 0.5 * stiffness * depth * depth};
}

}  // namespace haptic::engine
