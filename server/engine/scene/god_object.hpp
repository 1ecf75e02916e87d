#pragma once
// God-object (proxy) rendering of a triangle mesh (Zilles and Salisbury 1995, "A constraint-based
// god-object method for haptic display"; Ruspini, Kolarov and Khatib 1997, "The haptic display of
// complex graphical environments"). The proxy P is a point that follows the tool T through free
// space and stops on the surface where the tool goes in; the force pulls the tool toward it.
// Every triangle is two-sided, so a tool cannot push through a thin part (a single plate) from
// either side, however far it moves in one tick.
//
// Description apart from state: the mesh (MeshBvh) is immutable and may be shared; the proxy's
// state (GodObjectState) belongs to the loop, one per tool and mesh. The proxy is kept in the
// object frame O, so geometry that moves carries it.
//
// One tick (update_god_object), with g = p_OT the tool in O:
//   1. target x = argmin |x - g|^2 subject to the active constraint planes n_i . x >= c_i
//      (Zilles and Salisbury 1995 minimise this cost with Lagrange multipliers for up to three
//      planes; here the small QP is solved exactly by trying every subset of at most three planes
//      as equalities, each by its Gram system, and keeping the feasible candidate nearest g);
//   2. trace the segment from the proxy to x through the mesh (MeshBvh::first_hit);
//   3. nothing crossed: the proxy moves to x. With no constraints it has reached the tool (free).
//      Otherwise the constraints are dropped and the tool traced for again from the new position,
//      which lets the proxy leave a plane whose triangle has ended (a convex edge or vertex) and
//      find the next one (the repeated sub-goal updates of Ruspini et al. 1997);
//   4. a triangle crossed: the proxy stops before it, `margin` off its plane (or stays where it is
//      if it was already that close), and the plane, oriented toward the proxy's side, becomes a
//      constraint n . x >= n . a + margin; with four, the QP keeps only the active ones (<= 3);
//   5. repeat until the target equals the proxy (converged) or kGodObjectMaxIterations traces
//      were made.
// Every position the proxy takes is reached by a segment that crosses no triangle, so stopping
// early (the iteration bound) leaves it valid, merely behind; the next tick continues.
//
// Force (the material's K, B): F_T_W = max(0, K d - B v_n) u, with d = |p_WP - p_WT|,
// u = (p_WP - p_WT) / d and v_n = u . (v_WT - v_surface) the tool's approach speed relative to the
// object's surface point at the proxy. That is F = K (p_WP - p_WT) - B v with the damping taken
// along the contact direction and the total clamped so a surface only pushes, the contact law of
// evaluate_scene.cpp. In free space F = 0 and p_WP = p_WT exactly.
//
// Numerical margin: the proxy is kept at least `margin` (default 1e-6 m, so K = 1000 N/m
// shifts the force by 1 mN) off every plane it is constrained by; starting that far off,
// rounding (about 1e-16 m at 1 m) cannot move the proxy's side of a plane.
//
// Replacing the mesh while it is touched (rebase_god_object): the proxy keeps its last world
// position p_WP. If it was in contact, the new mesh is traced from p_WP + L n to p_WP, with n the
// last contact direction (from tool to proxy, unit) and L = params.replace_lift: a new surface
// between those points stops the proxy `margin` off it (the new surface has grown over the old
// contact), otherwise the proxy stays at p_WP and the next update traces from there to the tool
// (the surface has receded, or stayed). Either way the proxy moves by the geometry change along
// n, plus at most the margin, so the force changes by at most K (|change| + margin) while the
// change is below L and no other layer of the new mesh lies within L above the contact. A free
// proxy is left at the tool; a tool the new mesh swallows feels nothing until it leaves (no force
// is invented by a replacement).
//
// Cost bound: at most kGodObjectMaxIterations (12) segment traces and QP solves per tick; no
// allocation (the constraint planes are a fixed array of four, the BVH queries use a fixed stack
// of 64 node indices).

#include <cstdint>
#include <string>

#include "engine/core/vec3.hpp"
#include "engine/scene/mesh.hpp"

namespace haptic::engine {

/// Where the mesh is and how it moves, in W.
struct MeshPose {
  Vec3 p_WO;   // Object origin in W. Unit: m.
  Quat R_WO;   // Orientation in W (unit quaternion).
  Vec3 v_WO;   // Velocity of the object origin in W. Unit: m/s.
  Vec3 w_WO;   // Angular velocity of O in W. Unit: rad/s.
};

struct GodObjectParams {
  double stiffness = 0.0;       // K. Unit: N/m. >= 0.
  double damping = 0.0;         // B. Unit: N*s/m. >= 0.
  double margin = 1e-6;         // Distance kept off constraint planes. Unit: m. > 0.
  double replace_lift = 0.02;   // L of the replacement rule. Unit: m. >= 0.
};

/// The loop's state for one proxy on one mesh.
struct GodObjectState {
  Vec3 p_OP;               // Proxy in O. Unit: m.
  Vec3 p_WP;               // Proxy in W after the last update. Unit: m.
  Vec3 n_W;                // Last contact direction (tool to proxy, unit) in W; 0 when free.
  bool in_contact = false;
  bool initialized = false;  // False until reset_god_object or the first update.
};

/// At most this many segment traces (and QP solves) per tick.
inline constexpr std::uint32_t kGodObjectMaxIterations = 12;
/// Constraint planes held at once: three active plus the one just hit.
inline constexpr std::uint32_t kGodObjectMaxPlanes = 4;

struct GodObjectOutput {
  Vec3 F_T_W;                  // Force on the tool in W. Unit: N.
  Vec3 p_WP;                   // Proxy in W. Unit: m.
  bool in_contact = false;     // The proxy is held off the tool by the surface.
  std::uint32_t plane_count = 0;  // Active constraint planes at the end of the tick (<= 3).
  Vec3 normals_W[3];           // Their unit normals (toward the proxy's side) in W.
  std::uint32_t iterations = 0;   // Segment traces made (<= kGodObjectMaxIterations).
  bool input_rejected = false;    // p_WT, v_WT or the pose was not finite: zero force, state kept.
};

/// Puts the proxy at the tool (free), e.g. when the object appears. Does not allocate.
void reset_god_object(GodObjectState& state, const MeshPose& pose, const Vec3& p_WT);

/// One tick: moves the proxy toward the tool as far as the mesh allows and returns the force.
/// An uninitialized state is first reset at the tool. Does not allocate; never returns NaN.
GodObjectOutput update_god_object(GodObjectState& state, const MeshBvh& mesh,
                                  const MeshPose& pose, const GodObjectParams& params,
                                  const Vec3& p_WT, const Vec3& v_WT);

/// Call once when the mesh the proxy touches is replaced by `new_mesh` at `new_pose`, before the
/// first update with it (the rule is in the file comment). Does not allocate.
void rebase_god_object(GodObjectState& state, const MeshBvh& new_mesh, const MeshPose& new_pose,
                       const GodObjectParams& params);

/// Returns "" or a message naming the bad parameter (finite, K >= 0, B >= 0, margin > 0 and
/// <= 1e-3 m, replace_lift >= 0).
std::string validate_god_object_params(const GodObjectParams& params);

}  // namespace haptic::engine
