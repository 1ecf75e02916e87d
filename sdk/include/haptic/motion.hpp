#pragma once
// Between and beyond the samples: the tool's position at a server time a graphics frame needs,
// from the States the stream delivers (docs/architecture.md, "SDK"). Frames and units as State's:
// positions in W (m), velocities (m/s), server time (s).

#include "haptic/types.hpp"

namespace haptic {

/// The position at server time `t` between two samples `a` (earlier) and `b` (later), by cubic
/// Hermite interpolation on their positions and velocities: exact for any cubic path, and for a
/// smooth one in error O(h⁴) over the samples' gap h (linear interpolation is O(h²)). `t` outside
/// [a, b] extrapolates the same cubic; equal times give a's position.
Vec3 interpolate_position(const State& a, const State& b, double t);

/// The position at server time `t` ≥ latest's, extrapolated from the newest sample with the
/// acceleration the two newest imply: p + v Δ + ½ a Δ², a = (v_latest − v_previous) / h,
/// Δ = t − latest's time. Error O(Δ³) for a smooth path; samples with equal times give p + v Δ.
Vec3 predict_position(const State& previous, const State& latest, double t);

}  // namespace haptic
